// Every vector path of the kernels gives the bits of the plain C++ reference (issue 18, item 2;
// core/simd_dispatch.hpp): the material update on random states in every regime of the
// Drucker-Prager return, and whole runs of a granular collapse and of two elastic bodies.
#include "bit_identity.hpp"
#include "scene_fixtures.hpp"
#include "talus/core/error.hpp"
#include "talus/core/simd_dispatch.hpp"
#include "talus/solver/body_materials.hpp"
#include "talus/solver/solver.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

namespace talus {
namespace isa_paths_test {
namespace {

/// Selects an instruction-set path for the test's scope and goes back to "auto" after it.
struct IsaScope {
  explicit IsaScope(const std::string& name) { select_isa(name); }
  ~IsaScope() { select_isa("auto"); }
};

std::vector<std::string> vector_paths() {
  std::vector<std::string> paths = available_isas();
  paths.erase(paths.begin());  // "reference"
  return paths;
}

/// A block sliding down a terrain grid (the ProfileTerrain transfers), with the given solver keys.
Scene terrain_slide(const std::string& solver_keys) {
  const std::string json = R"({
    "grid": { "origin": [0, 0, 0], "size": [4, 0.25, 2], "cell_size": 0.25,
              "terrain": { "points": [[0, 2.0], [4, 0.0]] } },
    "time": { "end": 0.1, "courant": 0.3 },
    "solver": { )" + solver_keys + R"( },
    "materials": { "m": { "density": 1000.0, "young": 1.0e6, "poisson": 0.3 } },
    "bodies": [ { "name": "block", "material": "m", "particles_per_cell": 2,
                  "box": { "min": [1, 0, 0], "max": [2, 0.25, 0.75], "frame": "terrain" } } ],
    "boundaries": { "z-": { "type": "friction", "friction_coefficient": 0.2 }, "z+": "open",
                    "x-": "open", "x+": "open", "y-": "slip", "y+": "slip" }
  })";
  return parse_scene(json, "terrain_slide");
}

TEST(IsaPaths, TheReferenceAndAtLeastTheBaselineAreAvailable) {
  const std::vector<std::string> all = available_isas();
  ASSERT_GE(all.size(), 2u);
  EXPECT_EQ(all.front(), "reference");
  {
    IsaScope scope("reference");
    EXPECT_EQ(active_isa(), "reference");
    EXPECT_FALSE(vector_kernels_enabled());
  }
  for (const std::string& name : vector_paths()) {
    IsaScope scope(name);
    EXPECT_EQ(active_isa(), name);
    EXPECT_TRUE(vector_kernels_enabled());
  }
  EXPECT_EQ(active_isa(), all.back());  // auto: the best
}

TEST(IsaPaths, AnUnknownPathIsAnInputErrorNamingTheChoices) {
  try {
    select_isa("avx1024");
    FAIL() << "no error";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("avx1024"), std::string::npos) << message;
    EXPECT_NE(message.find("reference"), std::string::npos) << message;
    EXPECT_EQ(e.exit_code(), 2);
  }
  EXPECT_TRUE(vector_kernels_enabled());
}

TEST(IsaPaths, AnUnknownPathInTheEnvironmentIsAnErrorNamingTheVariable) {
  ::setenv("TALUS_ISA", "avx1024", 1);
  try {
    select_isa_from_environment();
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind("TALUS_ISA = 'avx1024'", 0), 0u) << message;
    EXPECT_EQ(e.exit_code(), 2);
  }
  ::unsetenv("TALUS_ISA");
  EXPECT_TRUE(vector_kernels_enabled());
}

// Particles of a Drucker-Prager sand with cohesion and a tension cut-off, of a rock and of μ(I)
// glass beads (runs of 37 particles each) in random states: inside
// the cone, beyond it (cone return), far in tension (apex and cut-off), separated (V > 1.5 V0), some
// flowing (the second model's alpha_g), and one non-finite increment. One chunk per call, as the
// solver makes them.
struct MaterialCase {
  ParticleStore particles;
  std::vector<StrainIncrements> chunks;
};

MaterialCase random_material_case(const Scene& scene, std::size_t n, unsigned seed) {
  MaterialCase c;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const std::size_t bodies = scene.bodies.size();
  for (std::size_t p = 0; p < n; ++p)
    c.particles.add(static_cast<std::int64_t>(p), Vec3::Zero(), Vec3::Zero(), 1.0, 1.0e-3,
                    static_cast<std::uint16_t>((p / 37) % bodies));  // runs of one body, then the next
  BodyMaterials(scene, c.particles);  // allocates the plastic state
  ParticleStore& P = c.particles;
  for (std::size_t p = 0; p < n; ++p) {
    // Mostly whole vector groups of one regime, with a few odd particles among them (the kernel
    // leaves their group to the reference) and runs of them.
    const bool tension = p % 89 == 0 || (p >= 500 && p < 560);
    const bool separating = p % 97 == 0 || (p >= 300 && p < 340);
    const double pressure = 2.0e4 * (0.5 + 0.5 * u(rng)) - (tension ? 3.0e4 : 0.0);
    const double deviator = (p % 5 == 0 ? 3.0 : 0.8) * 0.6 * std::abs(pressure) * (0.5 + 0.5 * u(rng));
    for (int k = 0; k < 3; ++k) P.stress[k][p] = -pressure + deviator * u(rng);
    for (int k = 3; k < 6; ++k) P.stress[k][p] = deviator * u(rng);
    P.plastic_strain[p] = 0.05 + 0.04 * u(rng);  // either side of flowing_plastic_strain
    if (separating) P.volume[p] = 1.6e-3;         // separated after the update
  }
  for (std::size_t begin = 0; begin < n; begin += StrainIncrements::kCapacity) {
    StrainIncrements inc;
    for (std::size_t k = 0; k < StrainIncrements::kCapacity; ++k) {
      const double scale = (k % 3 == 0 ? 1.0e-2 : 1.0e-4);
      for (int j = 0; j < 6; ++j) inc.strain[j][k] = scale * u(rng);
      for (int j = 0; j < 3; ++j) inc.spin[j][k] = scale * u(rng);
    }
    c.chunks.push_back(inc);
  }
  c.chunks[0].strain[0][5] = std::nan("");  // a non-finite increment goes to the reference too
  return c;
}

// Runs the update over all chunks on `isa`; returns the particles and the chunks' dissipation.
std::pair<ParticleStore, std::vector<double>> update_on(const std::string& isa, const Scene& scene, MaterialCase c) {
  IsaScope scope(isa);
  const BodyMaterials materials(scene, c.particles);
  std::vector<double> dissipated;
  const std::size_t n = c.particles.size();
  for (std::size_t b = 0; b * StrainIncrements::kCapacity < n; ++b) {
    const std::size_t begin = b * StrainIncrements::kCapacity;
    const std::size_t end = std::min(n, begin + StrainIncrements::kCapacity);
    dissipated.push_back(materials.update(c.particles, begin, end, c.chunks[b], 1.0e-4));
  }
  return {c.particles, dissipated};
}

Scene sand_and_rock_scene() {
  const std::string json = R"({
    "name": "materials",
    "grid": { "origin": [0, 0, 0], "size": [1, 1, 1], "cell_size": 0.1 },
    "time": { "end": 0.01 },
    "materials": {
      "sand": { "model": "drucker_prager", "density": 1600.0, "young": 2.0e6, "poisson": 0.3,
                "friction_angle": 30.0, "dilatancy_angle": 10.0, "cohesion": 200.0, "tension_cutoff": 50.0,
                "flowing_dilatancy_angle": 0.0 },
      "rock": { "density": 2600.0, "young": 5.0e7, "poisson": 0.25 },
      "beads": { "model": "mu_i", "density": 1500.0, "young": 2.0e6, "poisson": 0.3 } },
    "bodies": [ { "name": "a", "material": "sand", "box": { "min": [0.1, 0.1, 0.1], "max": [0.3, 0.3, 0.3] } },
                { "name": "b", "material": "rock", "box": { "min": [0.5, 0.5, 0.5], "max": [0.7, 0.7, 0.7] } },
                { "name": "c", "material": "beads", "box": { "min": [0.1, 0.5, 0.1], "max": [0.3, 0.7, 0.3] } } ]
  })";
  return parse_scene(json, "sand_and_rock_scene");
}

TEST(IsaPaths, MaterialUpdateGivesTheReferenceBitsInEveryRegime) {
  const Scene scene = sand_and_rock_scene();
  const MaterialCase start = random_material_case(scene, 1000, 7);
  const auto [reference, reference_dissipation] = update_on("reference", scene, start);
  for (const std::string& isa : vector_paths()) {
    const auto [lanes, dissipation] = update_on(isa, scene, start);
    for (int k = 0; k < 6; ++k) {
      EXPECT_TRUE(test::same_bits(lanes.stress[k], reference.stress[k])) << isa << " stress " << k;
      EXPECT_TRUE(test::same_bits(lanes.strain[k], reference.strain[k])) << isa << " strain " << k;
    }
    EXPECT_TRUE(test::same_bits(lanes.volume, reference.volume)) << isa;
    EXPECT_TRUE(test::same_bits(lanes.plastic_strain, reference.plastic_strain)) << isa;
    EXPECT_TRUE(test::same_bits(dissipation, reference_dissipation)) << isa;
  }
  // The case reaches every regime of both plastic models: some particles stayed elastic, some
  // returned or flowed, some separated or disconnected.
  for (std::uint16_t body : {0, 2}) {
    std::size_t returned = 0, unchanged = 0, zero_stress = 0;
    for (std::size_t p = 0; p < reference.size(); ++p) {
      if (reference.body[p] != body) continue;
      if (reference.plastic_strain[p] != start.particles.plastic_strain[p]) ++returned;
      else ++unchanged;
      if (reference.stress[0][p] == 0.0 && reference.stress[3][p] == 0.0) ++zero_stress;
    }
    EXPECT_GT(returned, 30u) << "body " << body;
    EXPECT_GT(unchanged, 30u) << "body " << body;
    EXPECT_GT(zero_stress, 5u) << "body " << body;
  }
}

void expect_every_path_matches_the_reference(const Scene& scene) {
  const Solver reference = [&] {
    IsaScope scope("reference");
    return test::run_to_end(scene, 1);
  }();
  for (const std::string& isa : vector_paths()) {
    IsaScope scope(isa);
    const Solver lanes = test::run_to_end(scene, 2);
    test::expect_same_particles_and_energies(reference, lanes, isa);
    EXPECT_TRUE(test::same_bits(lanes.particles().plastic_strain, reference.particles().plastic_strain)) << isa;
  }
}

TEST(IsaPaths, GranularCollapseIsBitIdenticalOnEveryPath) {
  expect_every_path_matches_the_reference(test::column_collapse_scene(0.02, 0.04));
}

TEST(IsaPaths, MuICollapseIsBitIdenticalOnEveryPath) {
  std::string json = R"({
    "grid": { "origin": [0, 0, 0], "size": [0.6, 0.02, 0.3], "cell_size": 0.02 },
    "time": { "end": 0.05, "courant": 0.3 },
    "materials": { "beads": { "model": "mu_i", "density": 1500.0, "young": 2.0e6, "poisson": 0.3 } },
    "bodies": [ { "name": "column", "material": "beads", "box": { "min": [0, 0, 0], "max": [0.1, 0.02, 0.2] },
                  "particles_per_cell": 2 } ],
    "boundaries": { "x-": "slip", "x+": "slip", "y-": "slip", "y+": "slip",
                    "z-": { "type": "friction", "friction_coefficient": 0.5 }, "z+": "open" }
  })";
  expect_every_path_matches_the_reference(parse_scene(json, "mu_i_column"));
}

TEST(IsaPaths, ElasticBodiesAreBitIdenticalOnEveryPath) {
  expect_every_path_matches_the_reference(test::tumbling_block_scene(0.002));
}

// The transfers of the other shapes and schemes: cpGIMP with USL, the B-spline with USF.
TEST(IsaPaths, EveryShapeAndSchemeIsBitIdenticalOnEveryPath) {
  Scene cpgimp = test::column_collapse_scene(0.02, 0.02);
  cpgimp.shape = ShapeKind::CpGimp;
  cpgimp.scheme = SchemeKind::Usl;
  expect_every_path_matches_the_reference(cpgimp);
  Scene bspline = test::column_collapse_scene(0.02, 0.02);
  bspline.shape = ShapeKind::BSpline2;
  bspline.scheme = SchemeKind::Usf;
  expect_every_path_matches_the_reference(bspline);
}

// The scatter into per-block boxes (solver.scatter = "block_buffers"): MUSL's P2G and remap with a
// linear shape on a terrain grid (the default flume's kind), and USF's two scatters with cpGIMP.
TEST(IsaPaths, BlockBufferScattersAreBitIdenticalOnEveryPath) {
  Scene usf = test::column_collapse_scene(0.02, 0.02);
  usf.shape = ShapeKind::CpGimp;
  usf.scheme = SchemeKind::Usf;
  usf.scatter = ScatterOrder::BlockBuffers;
  expect_every_path_matches_the_reference(usf);
  expect_every_path_matches_the_reference(
      terrain_slide(R"("shape": "linear", "scheme": "musl", "scatter": "block_buffers", "pic_fraction": 0.01)"));
}

// MLS strain smoothing (Edo & Matsubara 2015, eq. 38-46) in the run: the smoother's lanes are compiled per
// target too. A 3D linear fit on a cpGIMP column (MUSL), a quadratic fit over x and z only
// with a radius that is not a whole number of cells (USAVG), one linear fit per cell (B-spline), and
// the particle fit's weights reused (B-spline).
TEST(IsaPaths, MlsSmoothedRunsAreBitIdenticalOnEveryPath) {
  Scene linear = test::column_collapse_scene(0.02, 0.02);
  linear.shape = ShapeKind::CpGimp;
  linear.smoothing.enabled = true;
  linear.smoothing.mls.radius_factor = 1.5;
  expect_every_path_matches_the_reference(linear);
  Scene quadratic = test::column_collapse_scene(0.02, 0.01);
  quadratic.scheme = SchemeKind::Usavg;
  quadratic.smoothing.enabled = true;
  quadratic.smoothing.mls.basis = MlsBasis::Quadratic;
  quadratic.smoothing.mls.axes = {true, false, true};
  quadratic.smoothing.mls.radius_factor = 2.3;
  expect_every_path_matches_the_reference(quadratic);
  Scene by_cell = test::column_collapse_scene(0.02, 0.02);  // the one-fit-per-cell variant
  by_cell.shape = ShapeKind::BSpline2;
  by_cell.smoothing.enabled = true;
  by_cell.smoothing.mls.variant = MlsVariant::Cell;
  by_cell.smoothing.mls.radius_factor = 1.5;
  expect_every_path_matches_the_reference(by_cell);
  Scene reused = by_cell;  // the particle fit's weights reused between fits (its apply is per target too)
  reused.smoothing.mls.variant = MlsVariant::Reused;
  reused.smoothing.mls.reuse_strain = 1e-3;
  expect_every_path_matches_the_reference(reused);
}

// A Drucker-Prager block crossing the periodic x seam (the wrapped stencils), B-spline.
TEST(IsaPaths, PeriodicWrapIsBitIdenticalOnEveryPath) {
  const std::string json = R"({
    "grid": { "origin": [0, 0, 0], "size": [1.0, 0.5, 0.5], "cell_size": 0.0625 },
    "time": { "end": 0.05, "courant": 0.3 },
    "solver": { "shape": "bspline2" },
    "materials": { "sand": { "model": "drucker_prager", "density": 1600.0, "young": 2.0e6, "poisson": 0.3,
                             "friction_angle": 30.0, "cohesion": 10.0 } },
    "bodies": [ { "name": "block", "material": "sand", "particles_per_cell": 2, "velocity": [4.0, 0.5, 0],
                  "box": { "min": [0.75, 0, 0], "max": [1.0, 0.25, 0.25] } } ],
    "boundaries": { "x-": "periodic", "x+": "periodic", "y-": "periodic", "y+": "periodic",
                    "z-": { "type": "friction", "friction_coefficient": 0.5 }, "z+": "open" }
  })";
  expect_every_path_matches_the_reference(parse_scene(json, "periodic_block"));
}

// A block sliding down a terrain (the ProfileTerrain transfers), uGIMP, USAVG.
TEST(IsaPaths, TerrainTransfersAreBitIdenticalOnEveryPath) {
  expect_every_path_matches_the_reference(terrain_slide(R"("shape": "ugimp", "scheme": "usavg")"));
}

}  // namespace
}  // namespace isa_paths_test
}  // namespace talus
