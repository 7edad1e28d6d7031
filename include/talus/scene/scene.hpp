#pragma once
// The validated description of a run: plain structs, filled in and checked by scene_reader.cpp.
// Nothing below the solver reads JSON; everything it needs is here, with defaults resolved.
#include "talus/core/types.hpp"
#include "talus/grid/grid.hpp"

#include <array>
#include <string>
#include <vector>

namespace talus {

enum class ShapeKind { Linear };
enum class SchemeKind { Musl, Usl };

struct LinearElasticParameters {
  double young = 0.0;    // E [Pa]
  double poisson = 0.0;  // nu [-]
};

struct MaterialSpec {
  std::string name;
  double density = 0.0;  // initial density [kg/m^3]
  LinearElasticParameters elastic;
  /// P-wave (constrained) modulus M = K + 4G/3, which sets the wave speed c = sqrt(M / rho).
  double p_wave_modulus() const;
  double bulk_modulus() const;
  double shear_modulus() const;
};

struct BodySpec {
  std::string name;
  int material = 0;                      // index into Scene::materials
  Vec3 box_min = Vec3::Zero();           // axis-aligned box filled with particles
  Vec3 box_max = Vec3::Zero();
  int particles_per_cell = 2;            // n: n x n x n particles per cell
  Vec3 velocity = Vec3::Zero();          // initial velocity
};

enum class WallType { Open, Slip, Fixed, Friction };

struct WallSpec {
  WallType type = WallType::Slip;
  double friction_coefficient = 0.0;  // mu, only for Friction
};

struct OutputSpec {
  double frame_interval = 0.0;         // [s] between particle frames; 0 = first and last only
  double history_interval = 0.0;       // [s] between energy-history rows; 0 = every step
  bool compress = true;                // LZ4 inside the .vtu files
};

struct Scene {
  std::string name;
  std::string description;
  GridGeometry grid;
  Vec3 gravity{0.0, 0.0, -9.81};
  double end_time = 1.0;
  double courant = 0.3;                // seed 000 eq. 60: c dt / h
  int max_steps = 0;                   // 0 = no limit
  SchemeKind scheme = SchemeKind::Musl;
  ShapeKind shape = ShapeKind::Linear;
  int sort_interval = 20;              // re-sort at least this often (also when a particle drifts)
  std::vector<MaterialSpec> materials;
  std::vector<BodySpec> bodies;
  // walls[axis][side]: side 0 = lower face (x-, y-, z-), side 1 = upper face.
  std::array<std::array<WallSpec, 2>, 3> walls{};
  OutputSpec output;
};

const char* to_string(SchemeKind scheme);
const char* to_string(ShapeKind shape);
const char* to_string(WallType type);

}  // namespace talus
