#pragma once
// Single-point (element) tests of the Drucker–Prager model: a strain- or mixed-controlled loading
// path applied to one material point, as in Abe, Johansson & Konagai 2005, sec. 6(3) and Fig. 13. The command
// `talus element-test SPEC.json --out FILE.csv` reads the spec (src/app/element_test_command.cpp)
// and calls run_element_test(); the CSV columns are documented in docs/drucker-prager.md.
//
// Axes: y is the axial (vertical) direction; simple shear shears x along y (gamma_xy) with y the
// normal of the shear plane. Stress positive in tension in all outputs except the columns p and
// q; the spec's strains and pressures are given in the natural sign of each test (below).
#include "talus/core/types.hpp"
#include "talus/material/drucker_prager.hpp"

#include <iosfwd>
#include <vector>

namespace talus {

enum class ElementPath {
  /// Axial strain eps_yy prescribed; lateral stresses xx, zz held at 0; starts stress-free.
  UniaxialCompression,
  /// Engineering shear strain gamma_xy = 2 eps_xy prescribed; sigma_yy held at -pressure
  /// (constant normal stress); eps_xx = eps_zz = eps_yz = eps_xz = 0; starts at -pressure I.
  /// eps_v = eps_yy is then the volumetric strain (dilatancy, Abe, Johansson & Konagai 2005, Fig. 13 right).
  SimpleShear,
  /// Axial strain prescribed; lateral stresses held at -pressure (the confining pressure);
  /// starts at -pressure I.
  DrainedTriaxial,
  /// Axial strain prescribed, all other strains zero (uniaxial strain); starts at -pressure I.
  Oedometer,
};

struct ElementTestSpec {
  DruckerPragerParameters material;
  ElementPath path = ElementPath::UniaxialCompression;
  /// Compression-positive pressure [Pa] >= 0: confining pressure (drained triaxial), normal stress
  /// (simple shear), initial isotropic pressure (oedometer); must be 0 for uniaxial compression.
  double pressure = 0.0;
  /// Successive targets of the control strain, starting from 0: axial SHORTENING (compression
  /// positive, eps_yy = -value) for the compression paths, engineering shear strain gamma_xy for
  /// simple shear. One entry is a monotonic test; more entries give unloading / reversal legs.
  std::vector<double> strain_targets;
  /// Total number of increments over the whole path, shared among the legs in proportion to
  /// their length (each leg at least one).
  int increments = 100;
  /// Simple shear only: apply the path's spin w_xy = d gamma / 2 to the stress and back stress
  /// (Jaumann rate, as the MPM loop does). The other paths have no spin.
  bool spin = true;
};

struct ElementTestPoint {
  int step = 0;
  Sym6 strain = Sym6::Zero();  ///< accumulated strain increments (tensor components)
  Sym6 stress = Sym6::Zero();  ///< tension positive
  double equivalent_plastic_strain = 0.0;
  double yield_function = 0.0;
  DruckerPragerResult::Regime regime = DruckerPragerResult::Regime::Elastic;
  double plastic_work = 0.0;  ///< cumulative sum of sigma : d_eps^p [J/m^3]
  Sym6 back_stress = Sym6::Zero();
};

/// Runs the path; the first point is the initial state (step 0). Mixed control (the stress-held
/// components) is solved per increment by Newton's method on the unknown strain components with
/// the algorithmic (consistent) tangent of DruckerPrager::update, taken by finite differences;
/// converged when the held stresses are within 1e-12 of the stress scale. Throws talus::Error
/// (instability) naming the increment if Newton does not converge.
std::vector<ElementTestPoint> run_element_test(const ElementTestSpec& spec);

/// Writes the points as CSV with a header row (columns: docs/drucker-prager.md).
void write_element_test_csv(std::ostream& out, const std::vector<ElementTestPoint>& points);

/// Name of a regime as written in the CSV: elastic, cone, apex, tension_cutoff.
const char* regime_name(DruckerPragerResult::Regime regime);

}  // namespace talus
