#include "talus/scene/scene.hpp"

#include <fmt/core.h>

namespace talus {

double MaterialSpec::bulk_modulus() const {
  return elastic.young / (3.0 * (1.0 - 2.0 * elastic.poisson));
}
double MaterialSpec::shear_modulus() const { return elastic.young / (2.0 * (1.0 + elastic.poisson)); }
double MaterialSpec::p_wave_modulus() const { return bulk_modulus() + 4.0 / 3.0 * shear_modulus(); }

const char* to_string(SchemeKind scheme) {
  switch (scheme) {
    case SchemeKind::Musl: return "musl";
    case SchemeKind::Usl: return "usl";
    case SchemeKind::Usf: return "usf";
    case SchemeKind::Usavg: return "usavg";
  }
  return "?";
}

const char* to_string(ShapeKind shape) {
  switch (shape) {
    case ShapeKind::Linear: return "linear";
    case ShapeKind::UGimp: return "ugimp";
    case ShapeKind::CpGimp: return "cpgimp";
    case ShapeKind::BSpline2: return "bspline2";
  }
  return "?";
}

const char* to_string(MaterialModel model) {
  switch (model) {
    case MaterialModel::LinearElastic: return "linear_elastic";
    case MaterialModel::DruckerPrager: return "drucker_prager";
    case MaterialModel::MuI: return "mu_i";
  }
  return "?";
}

const char* to_string(ConeFit cone) {
  switch (cone) {
    case ConeFit::PlaneStrain: return "plane_strain";
    case ConeFit::Compression: return "compression";
    case ConeFit::Extension: return "extension";
    case ConeFit::Inscribed: return "inscribed";
  }
  return "?";
}

const char* to_string(BodyShapeKind shape) {
  switch (shape) {
    case BodyShapeKind::Box: return "box";
    case BodyShapeKind::Prism: return "prism";
  }
  return "?";
}

const char* to_string(WallType type) {
  switch (type) {
    case WallType::Open: return "open";
    case WallType::Slip: return "slip";
    case WallType::Fixed: return "fixed";
    case WallType::Friction: return "friction";
  }
  return "?";
}

std::vector<std::string> scene_warnings(const Scene& scene) {
  std::vector<std::string> warnings;
  const double radius = scene.smoothing.mls.radius_factor;
  if (scene.smoothing.enabled && radius > kMlsStableRadiusFactor)
    warnings.push_back(fmt::format(
        "solver.smoothing.radius_factor = {} is above {} cells: MLS smoothing at 3 cells and more went unstable on "
        "the column (1.2 s) and the sliding block (docs/verification.md, \"MLS radius\")",
        radius, kMlsStableRadiusFactor));
  return warnings;
}

}  // namespace talus
