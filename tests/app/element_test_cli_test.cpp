// `talus element-test`: runs the built program on a shipped spec and on bad specs.
#include "program_fixture.hpp"

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace element_test_cli_test {
namespace {

namespace fs = std::filesystem;

using Result = talus::test::ProgramResult;
using talus::test::slurp;

class ElementTestCli : public talus::test::ProgramTest {};

const char* kGoodMaterial =
    R"("material": {"young": 2.0e6, "poisson": 0.3, "friction_angle": 40.0, "cohesion": 10.0})";

TEST_F(ElementTestCli, WritesTheCsvForAShippedSpec) {
  const fs::path spec =
      fs::path(TALUS_SOURCE_DIR) / "inputs" / "element_tests" / "fig13b_simple_shear_psi10.json";
  const fs::path csv = dir_ / "shear.csv";
  const Result r = run("element-test \"" + spec.string() + "\" --out \"" + csv.string() + "\"");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_TRUE(fs::exists(csv));
  std::ifstream in(csv);
  std::string header, line, last;
  std::getline(in, header);
  EXPECT_EQ(header.rfind("step,eps_xx,eps_yy,eps_zz,eps_yz,eps_xz,eps_xy,sig_xx", 0), 0u) << header;
  int rows = 0;
  while (std::getline(in, line)) {
    ++rows;
    last = line;
  }
  EXPECT_EQ(rows, 1001);  // initial state + 1000 increments
  EXPECT_NE(last.find(",cone,"), std::string::npos) << last;
  // eps_v (column 14) is positive: the sand dilates with psi = 10 degrees.
  std::stringstream fields(last);
  std::string field;
  for (int i = 0; i < 14; ++i) std::getline(fields, field, ',');
  EXPECT_GT(std::stod(field), 0.01);
}

TEST_F(ElementTestCli, OutOfRangeValueExitsTwoWithOneLine) {
  const fs::path spec = write(
      "bad.json", R"({"material": {"young": 2.0e6, "poisson": 0.3, "friction_angle": 95.0},
                     "path": {"type": "oedometer", "strain": 0.01, "increments": 10}})");
  const Result r = run("element-test \"" + spec.string() + "\" --out \"" + (dir_ / "x.csv").string() + "\"");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("material.friction_angle = 95"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("allowed (0, 90)"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "x.csv"));
}

TEST_F(ElementTestCli, UnknownKeyAndBadPathValuesExitTwoNamingTheKey) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {std::string("{") + kGoodMaterial +
           R"(, "path": {"type": "simple_shear", "normal_stress": 1e4, "strian": 0.1, "increments": 10}})",
       "unknown key path.strian"},
      {std::string("{") + kGoodMaterial +
           R"(, "path": {"type": "drained_triaxial", "confining_pressure": 1e5, "strain": 0.1, "increments": 0}})",
       "path.increments = 0 is outside the allowed range [1, 10000000]"},
      {std::string("{") + kGoodMaterial +
           R"(, "path": {"type": "drained_triaxial", "confining_pressure": -1, "strain": 0.1, "increments": 5}})",
       "path.confining_pressure = -1 is outside the allowed range (0, inf)"},
      {std::string("{") + kGoodMaterial +
           R"(, "path": {"type": "uniaxial_compression", "strain": [0.01, 2.0], "increments": 5}})",
       "path.strain[1] = 2 is outside the allowed range [-1, 1]"},
      {std::string("{") + kGoodMaterial + R"(, "path": {"type": "torsion", "strain": 0.1, "increments": 5}})",
       "path.type = \"torsion\" is not one of: uniaxial_compression, simple_shear"},
      {R"({"material": {"young": 1e6, "poisson": 0.3, "friction_angle": 30, "cone": "outer"}, "path": {}})",
       "material.cone = \"outer\" is not one of: plane_strain, compression"},
      {R"({"material": {"young": 1e6, "poisson": 0.3}})", "missing required key material.friction_angle"},
      {"{ not json", "malformed JSON"},
  };
  int i = 0;
  for (const auto& [text, expected] : cases) {
    const fs::path spec = write("case" + std::to_string(i++) + ".json", text);
    const Result r = run("element-test \"" + spec.string() + "\" --out \"" + (dir_ / "x.csv").string() + "\"");
    EXPECT_EQ(r.exit_code, 2) << expected;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(expected), std::string::npos) << "expected '" << expected << "' in: " << r.err;
  }
}

// `-o SPEC` replaced the spec with the CSV, and an unwritable --out was found only after the test ran.
TEST_F(ElementTestCli, OutputThatIsTheSpecOrCannotBeWrittenIsRefusedBeforeAnyWork) {
  const std::string text = slurp(fs::path(TALUS_SOURCE_DIR) / "inputs" / "element_tests" / "fig13b_simple_shear_psi10.json");
  const fs::path spec = write("spec.json", text);
  const Result same = run("element-test \"" + spec.string() + "\" -o \"" + spec.string() + "\"");
  EXPECT_EQ(same.exit_code, 2);
  EXPECT_EQ(same.out, "");
  EXPECT_EQ(same.err, "talus: error: --out " + spec.string() + " is the spec file itself; write the CSV to another file\n");
  EXPECT_EQ(slurp(spec), text);
  // the same file by another name
  const Result dotted = run("element-test \"" + spec.string() + "\" -o \"" + (dir_ / "." / "spec.json").string() + "\"");
  EXPECT_EQ(dotted.exit_code, 2);
  EXPECT_NE(dotted.err.find("is the spec file itself"), std::string::npos) << dotted.err;
  EXPECT_EQ(slurp(spec), text);
  const std::string missing = (dir_ / "no_such_folder" / "x.csv").string();
  const Result unwritable = run("element-test \"" + spec.string() + "\" -o \"" + missing + "\"");
  EXPECT_EQ(unwritable.exit_code, 2);
  EXPECT_EQ(unwritable.out, "");
  EXPECT_EQ(unwritable.err, "talus: error: --out " + missing + ": cannot write there: the folder " +
                                (dir_ / "no_such_folder").string() + " does not exist\n");
}

TEST_F(ElementTestCli, MissingSpecFileExitsTwo) {
  const Result r = run("element-test \"" + (dir_ / "nope.json").string() + "\" --out \"" +
                    (dir_ / "x.csv").string() + "\"");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("nope.json"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace element_test_cli_test
