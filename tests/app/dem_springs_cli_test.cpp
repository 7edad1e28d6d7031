// `talus dem-springs` as a user runs it: one JSON object on success, exit code 2 and one line on
// stderr for a continuum the packing cannot represent. Expected values come from the Abe 1996
// formulas written out here, not from the library.
#include "program_fixture.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <numbers>
#include <string>

namespace dem_springs_cli_test {
namespace {

using talus::test::ProgramResult;

int line_count(const std::string& text) {
  int lines = 0;
  for (char c : text) lines += (c == '\n');
  return lines;
}

class DemSpringsCli : public talus::test::ProgramTest {};

void expect_refused(const ProgramResult& r, const std::string& start) {
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(r.out.empty()) << r.out;
  EXPECT_EQ(line_count(r.err), 1) << r.err;
  EXPECT_EQ(r.err.rfind("talus: error: " + start, 0), 0u) << r.err;
}

TEST_F(DemSpringsCli, HexPrintsEq34SpringsAsJson) {
  const double young = 1.0e7, nu = 0.2;
  const ProgramResult r = run("dem-springs --E 1e7 --nu 0.2 --packing hex");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  const double shear = young / (2.0 * (1.0 + nu));
  const double kn = 2.0 / std::sqrt(3.0) * shear / (1.0 - 2.0 * nu);  // Abe 1996, eq. 34
  EXPECT_NEAR(j.at("kN").get<double>() / kn, 1.0, 1e-14);
  EXPECT_NEAR(j.at("kT").get<double>() / (kn * (1.0 - 4.0 * nu)), 1.0, 1e-14);
  EXPECT_EQ(j.at("packing"), "hex");
}

TEST_F(DemSpringsCli, ShearModulusIsAnAlternativeToYoungsModulus) {
  const ProgramResult from_e = run("dem-springs --E 2.6e7 --nu 0.3 --packing hex --plane-stress");
  const ProgramResult from_g = run("dem-springs --G 1e7 --nu 0.3 --packing hex --plane-stress");
  ASSERT_EQ(from_e.exit_code, 0) << from_e.err;
  ASSERT_EQ(from_g.exit_code, 0) << from_g.err;
  const auto e = nlohmann::json::parse(from_e.out);
  const auto g = nlohmann::json::parse(from_g.out);
  EXPECT_NEAR(e.at("kN").get<double>() / g.at("kN").get<double>(), 1.0, 1e-14);
  // Plane stress: eq. 34 with nu read as nu/(1+nu).
  const double nu_star = 0.3 / 1.3;
  EXPECT_NEAR(g.at("kN").get<double>() / (2.0 / std::sqrt(3.0) * 1e7 / (1.0 - 2.0 * nu_star)), 1.0, 1e-14);
  expect_refused(run("dem-springs --nu 0.3 --packing hex"), "give exactly one of --E and --G");
}

TEST_F(DemSpringsCli, Random3dNeedsARadiusAndUsesTheUniformStrainRelation) {
  const ProgramResult r = run("dem-springs --E 5e7 --nu 0.1 --packing random3d --radius 0.002");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  const double alpha = j.at("kT").get<double>() / j.at("kN").get<double>();
  EXPECT_NEAR((1.0 - alpha) / (4.0 + alpha), 0.1, 1e-14);
  // E = phi Z kN (2 kN + 3 kT) / (2 pi a (4 kN + kT)) with the defaults phi = 0.64, Z = 6.
  const double kn = j.at("kN").get<double>();
  const double young = 0.64 * 6.0 * kn * (2.0 + 3.0 * alpha) / (2.0 * std::numbers::pi * 0.002 * (4.0 + alpha));
  EXPECT_NEAR(young / 5e7, 1.0, 1e-13);
  expect_refused(run("dem-springs --E 5e7 --nu 0.1 --packing random3d"), "--radius is required");
}

TEST_F(DemSpringsCli, PoissonRatioAboveTheLimitExitsWithCode2AndOneLine) {
  expect_refused(run("dem-springs --E 1e7 --nu 0.3 --packing hex"), "--nu = 0.3 is above the limit 0.25");
  expect_refused(run("dem-springs --E 1e7 --nu 0.26 --packing random2d"), "--nu = 0.26 is above the limit 0.25");
  expect_refused(run("dem-springs --E 1e7 --nu 0.26 --packing random3d --radius 0.01"),
                 "--nu = 0.26 is above the limit 0.25");
  expect_refused(run("dem-springs --E 1e7 --nu 0.34 --packing hex --plane-stress"),
                 "--nu = 0.34 is above the limit 0.333333");
  expect_refused(run("dem-springs --E 1e7 --nu 0.1 --packing square"), "--nu = 0.1 cannot be represented");
  const ProgramResult square = run("dem-springs --E 1e7 --nu 0 --packing square");
  ASSERT_EQ(square.exit_code, 0) << square.err;
  const auto j = nlohmann::json::parse(square.out);
  EXPECT_DOUBLE_EQ(j.at("kN").get<double>(), 1e7);  // Abe 1996, eq. 31: kN = kT = E
  EXPECT_DOUBLE_EQ(j.at("kT").get<double>(), 1e7);
}

// With --E, G = E / (2 (1 + nu)) comes from nu: nu = nan or -1 was reported as "G = nan (from --E
// or --G)", which named neither --nu nor its range.
TEST_F(DemSpringsCli, PoissonRatioOutsideTheStableRangeIsNamedBeforeTheShearModulus) {
  for (const std::string nu : {"nan", "-1", "-5", "0.5"})
    expect_refused(run("dem-springs --E 1e9 --nu " + nu + " --packing hex"), "--nu = " + nu + " is outside (-1, 0.5)");
}

// Finite inputs whose springs a double cannot hold printed "kN": null and exited 0.
TEST_F(DemSpringsCli, SpringsBeyondTheRangeOfADoubleAreRefusedNamingTheInputs) {
  expect_refused(run("dem-springs --E 1e300 --nu 0.2 --packing random3d --radius 1e10"),
                 "kN = inf: the springs of --E = 1e+300 and --radius = 1e+10 are beyond the range of a double");
  expect_refused(run("dem-springs --E 1e-320 --nu 0.2 --packing random3d --radius 1e-10"),
                 "kT_over_kN = nan: the springs of --E = 1e-320 and --radius = 1e-10 are beyond the range of a double");
  expect_refused(run("dem-springs --G 1e308 --nu 0.2 --packing hex"),
                 "kN = inf: the springs of --G = 1e+308 are beyond the range of a double");
  // a subnormal spring has lost its digits (kT/kN printed 0.19975 for 0.2)
  expect_refused(run("dem-springs --E 1e-320 --nu 0.2 --packing hex"),
                 "kN = 8.014e-321: the springs of --E = 1e-320 are beyond the range of a double");
}

}  // namespace
}  // namespace dem_springs_cli_test
