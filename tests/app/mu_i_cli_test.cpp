// μ(I) through the talus program (issue 21): the shipped element test reproduces τ/p = μ(I) to
// 1e-10 relative over I = 1e-4 ... 1, and bad μ(I) parameters give one-line errors, exit 2.
#include "program_fixture.hpp"

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace mu_i_cli_test {
namespace {

namespace fs = std::filesystem;

using Result = talus::test::ProgramResult;
using talus::test::slurp;

class MuICli : public talus::test::ProgramTest {};

const std::string kInputs = std::string(TALUS_SOURCE_DIR) + "/inputs/";

TEST_F(MuICli, ElementTestReproducesMuOfIWithinTenToTheMinusTen) {
  const fs::path csv = dir_ / "mu_i.csv";
  const Result r = run("element-test \"" + kInputs + "element_tests/mu_i_simple_shear.json\" --out \"" + csv.string() + "\"");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "I,shear_rate,dt,p,tau,tau_over_p,mu_analytic,relative_error,plastic_shear_rate,last_change");
  int rows = 0;
  double i_min = 1e30, i_max = 0.0, worst = 0.0;
  constexpr double kMuS = 0.3818628674187188, kMu2 = 0.6434683848584607, kI0 = 0.279;
  while (std::getline(in, line)) {
    std::vector<double> v;
    std::stringstream fields(line);
    std::string f;
    while (std::getline(fields, f, ',')) v.push_back(std::stod(f));
    ASSERT_EQ(v.size(), 10u) << line;
    ++rows;
    const double i = v[0], p = v[3], tau = v[4], shear_rate = v[1], plastic_rate = v[8];
    i_min = std::min(i_min, i);
    i_max = std::max(i_max, i);
    // the analytic law evaluated here, independently of the program (Jop et al. 2006, the friction law)
    const double mu = kMuS + (kMu2 - kMuS) / (1.0 + kI0 / i);
    worst = std::max(worst, std::abs(tau / p / mu - 1.0));
    EXPECT_LT(std::abs(tau / p / mu - 1.0), 1e-10) << "I = " << i;
    EXPECT_NEAR(p, 1.0e3, 1e-9);  // constant pressure
    EXPECT_NEAR(plastic_rate / shear_rate, 1.0, 1e-9) << "I = " << i;  // steady: all of the shear is plastic
  }
  EXPECT_EQ(rows, 41);
  EXPECT_NEAR(i_min, 1e-4, 1e-18);
  EXPECT_NEAR(i_max, 1.0, 1e-14);
  std::printf("[ measured ] mu(I) element test: largest |tau/p / mu(I) - 1| = %.2e\n", worst);
}

TEST_F(MuICli, BadElementTestParameterExitsTwoNamingTheKey) {
  const fs::path spec = write("bad.json", R"({"material": {"model": "mu_i", "young": 1e7, "poisson": 0.3, "mu_s": 0.5, "mu_2": 0.4},
      "path": {"type": "mu_i_shear", "pressure": 1e3, "inertial_number": {"min": 1e-3, "max": 1, "count": 3}}})");
  const Result r = run("element-test \"" + spec.string() + "\" --out \"" + (dir_ / "x.csv").string() + "\"");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("material.mu_2 = 0.4 is out of range; allowed mu_2 > mu_s = 0.5"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "x.csv"));
  // one value from a range of two: it took min and ignored max without a word
  const fs::path one = write("one.json", R"({"material": {"model": "mu_i", "young": 1e7, "poisson": 0.3},
      "path": {"type": "mu_i_shear", "pressure": 1e3, "inertial_number": {"min": 1e-3, "max": 1, "count": 1}}})");
  const Result r1 = run("element-test \"" + one.string() + "\" --out \"" + (dir_ / "x.csv").string() + "\"");
  EXPECT_EQ(r1.exit_code, 2);
  EXPECT_EQ(r1.err, "talus: error: path.inertial_number.count = 1 gives one inertial number, but min = 0.001 and max = 1 "
                    "differ; give max = min, or a count of 2 or more\n");
  EXPECT_FALSE(fs::exists(dir_ / "x.csv"));
  // max below min: "max = 0.001 is outside the allowed range [0.01, inf)" hid where 0.01 came from
  const fs::path reversed = write("reversed.json", R"({"material": {"model": "mu_i", "young": 1e7, "poisson": 0.3},
      "path": {"type": "mu_i_shear", "pressure": 1e3, "inertial_number": {"min": 0.01, "max": 0.001, "count": 3}}})");
  const Result r2 = run("element-test \"" + reversed.string() + "\" --out \"" + (dir_ / "x.csv").string() + "\"");
  EXPECT_EQ(r2.exit_code, 2);
  EXPECT_EQ(r2.err, "talus: error: path.inertial_number.max = 0.001 is below path.inertial_number.min = 0.01: give "
                    "max >= min\n");
  EXPECT_FALSE(fs::exists(dir_ / "x.csv"));
}

// A spec whose total shear strain is below the elastic approach to mu(I_max) p (p = 100 MPa with the
// shipped strain of 0.1: 15 needed) leaves the samples elastic and tau/p 99% low with every number
// finite: the command warns, naming the keys, and, the error being above the tolerance 1e-10, exits 3
// with the CSV kept (it exited 0); the shipped spec (0.00015 needed) gets no warning.
TEST_F(MuICli, AStrainTooSmallToReachSteadyFlowIsWarnedAbout) {
  const std::string shipped = slurp(kInputs + "element_tests/mu_i_simple_shear.json");
  const std::string key = "\"pressure\": 1.0e3";
  ASSERT_NE(shipped.find(key), std::string::npos);
  std::string stiff = shipped;
  stiff.replace(stiff.find(key), key.size(), "\"pressure\": 1.0e8");
  const fs::path csv = dir_ / "x.csv";
  const Result warned = run("element-test \"" + write("p1e8.json", stiff).string() + "\" --out \"" + csv.string() + "\"");
  EXPECT_EQ(warned.exit_code, 3) << warned.err;
  EXPECT_EQ(std::count(warned.err.begin(), warned.err.end(), '\n'), 2) << warned.err;
  EXPECT_NE(warned.err.find("talus: warning: path.increments x path.strain_increment = 0.1 is below the shear strain 15"),
            std::string::npos)
      << warned.err;
  EXPECT_NE(warned.err.find("talus: error: element-test: mu(I) simple shear: |tau/p / mu(I) - 1| = 0.99"),
            std::string::npos)
      << warned.err;
  EXPECT_NE(warned.err.find("is above the tolerance 1e-10: the sample had not reached steady flow"), std::string::npos)
      << warned.err;
  EXPECT_TRUE(fs::exists(csv));  // kept, and said so
  EXPECT_NE(warned.err.find("the CSV is kept in " + csv.string()), std::string::npos) << warned.err;
  const Result quiet = run("element-test \"" + kInputs + "element_tests/mu_i_simple_shear.json\" --out \"" + csv.string() + "\"");
  EXPECT_EQ(quiet.exit_code, 0) << quiet.err;
  EXPECT_EQ(quiet.err, "");
}

// mu_2 = 1e6 (a hunt's): mu(I) p reaches 7.8e8 Pa, far beyond the elastic approach of the shipped
// strain, and the approach contracts by mu'B / (1 + mu'B), nearly 1, a step: tau/p was written up to
// 100% below mu(I) after the shortfall's warning, with exit code 0. Now exit 3, the CSV kept.
TEST_F(MuICli, AnErrorAboveTheToleranceExitsThreeAndKeepsTheCsv) {
  const std::string shipped = slurp(kInputs + "element_tests/mu_i_simple_shear.json");
  const std::string key = "\"mu_2\": 0.6434683848584607";
  ASSERT_NE(shipped.find(key), std::string::npos);
  std::string steep = shipped;
  steep.replace(steep.find(key), key.size(), "\"mu_2\": 1e6");
  const fs::path csv = dir_ / "mu2.csv";
  const Result r = run("element-test \"" + write("mu2.json", steep).string() + "\" --out \"" + csv.string() + "\"");
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 2) << r.err;
  EXPECT_NE(r.err.find("talus: warning: path.increments x path.strain_increment = 0.1 is below"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("talus: error: element-test: mu(I) simple shear: |tau/p / mu(I) - 1| = "), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("above the tolerance 1e-10"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(csv));
}

// J2 squares the stress: at p = 1e-300 Pa the steady shear stress squared to zero and the CSV was
// full of NaN, with exit code 0. The limit is where mu(I_min) p reaches 1e-150 Pa; just above it every
// value is finite and tau/p is mu(I).
TEST_F(MuICli, PressureTooSmallForADoubleIsRefusedWithTheLimitThatWorks) {
  const std::string shipped = slurp(kInputs + "element_tests/mu_i_simple_shear.json");
  const std::string key = "\"pressure\": 1.0e3";
  ASSERT_NE(shipped.find(key), std::string::npos);
  auto with_pressure = [&](const std::string& p) {
    std::string text = shipped;
    text.replace(text.find(key), key.size(), "\"pressure\": " + p);
    return write("p" + p + ".json", text);
  };
  const fs::path csv = dir_ / "x.csv";
  const Result tiny = run("element-test \"" + with_pressure("1e-300").string() + "\" --out \"" + csv.string() + "\"");
  EXPECT_EQ(tiny.exit_code, 2);
  EXPECT_EQ(std::count(tiny.err.begin(), tiny.err.end(), '\n'), 1) << tiny.err;
  EXPECT_NE(tiny.err.find("path.pressure = 1e-300 is out of range; allowed p >= 2.6181e-150 Pa"), std::string::npos)
      << tiny.err;
  EXPECT_FALSE(fs::exists(csv));
  const Result at_limit = run("element-test \"" + with_pressure("2.62e-150").string() + "\" --out \"" + csv.string() + "\"");
  ASSERT_EQ(at_limit.exit_code, 0) << at_limit.err;
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::stringstream fields(line);
    std::string f;
    std::vector<double> v;
    while (std::getline(fields, f, ',')) v.push_back(std::stod(f));
    ASSERT_EQ(v.size(), 10u) << line;
    for (const double x : v) EXPECT_TRUE(std::isfinite(x)) << line;
    EXPECT_LT(std::abs(v[7]), 1e-12) << line;  // relative_error of tau/p against mu(I)
  }
}

// Each bad value in the shipped μ(I) scene: exit 2, one line naming materials.beads.<key> and its
// range, no output folder.
TEST_F(MuICli, BadSceneParametersExitTwoNamingTheKeyAndRange) {
  const std::string scene = slurp(kInputs + "column_collapse_mu_i.json");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"\"mu_2\": 0.6434683848584607", "materials.beads.mu_2 = 0.3 is out of range; allowed mu_2 > mu_s"},
      {"\"i0\": 0.279", "materials.beads.i0 = 0 is out of range; allowed I0 > 0"},
      {"\"grain_diameter\": 0.53e-3", "materials.beads.grain_diameter = -1 is out of range; allowed d > 0"},
      {"\"grain_density\": 2450.0", "materials.beads.grain_density = 0 is out of range; allowed rho_s > 0"},
  };
  const std::vector<std::string> replacements = {"\"mu_2\": 0.3", "\"i0\": 0", "\"grain_diameter\": -1", "\"grain_density\": 0"};
  for (std::size_t k = 0; k < cases.size(); ++k) {
    std::string text = scene;
    const std::size_t at = text.find(cases[k].first);
    ASSERT_NE(at, std::string::npos) << cases[k].first;
    text.replace(at, cases[k].first.size(), replacements[k]);
    const fs::path file = write("bad" + std::to_string(k) + ".json", text);
    const fs::path out = dir_ / ("out" + std::to_string(k));
    const Result r = run("run \"" + file.string() + "\" --out \"" + out.string() + "\"");
    EXPECT_EQ(r.exit_code, 2) << cases[k].second;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(cases[k].second), std::string::npos) << "expected '" << cases[k].second << "' in: " << r.err;
    EXPECT_FALSE(fs::exists(out));
  }
}

}  // namespace
}  // namespace mu_i_cli_test
