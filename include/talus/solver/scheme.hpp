#pragma once
// The four update schemes as data: one row per scheme says which phases a step runs and with what
// share of the time step. Solver::step_with reads the row; adding a scheme is adding a row (and a
// name in scene.hpp), not threading a new flag through the step (docs/architecture.md).
//
//   MUSL   P2G, grid, G2P, remap, stress from v^{k+1}        (Sulsky et al. 1995; Edo & Matsubara
//                                                            2015, eq. 47-56)
//   USL    P2G, grid, G2P, stress from v^L                   (Sulsky's original)
//   USF    P2G of mass and momentum, stress from the start-of-step nodal velocities, force P2G,
//          grid, G2P; no stress update at the end            (Bardenhagen 2002)
//   USAVG  the USF stress update with dt/2 at the start, the MUSL update with dt/2 at the end
//                                                            (Nairn 2003)
#include "talus/scene/scene.hpp"

namespace talus {

struct SchemeSteps {
  /// Update the stress from the start-of-step nodal velocities before the internal force is
  /// scattered (the force is then that of the updated stress).
  bool stress_first = false;
  /// After G2P, scatter the particles' new momentum and form v^{k+1} = sum m_p v_p N / m (the
  /// remap); the end-of-step strain uses v^{k+1} instead of v^L.
  bool remap = false;
  /// Update the stress at the end of the step.
  bool stress_last = true;
  /// The share of dt that each stress update integrates.
  double stress_dt_share = 1.0;
};

constexpr SchemeSteps scheme_steps(SchemeKind scheme) {
  switch (scheme) {
    case SchemeKind::Musl: return {.stress_first = false, .remap = true, .stress_last = true, .stress_dt_share = 1.0};
    case SchemeKind::Usl: return {.stress_first = false, .remap = false, .stress_last = true, .stress_dt_share = 1.0};
    case SchemeKind::Usf: return {.stress_first = true, .remap = false, .stress_last = false, .stress_dt_share = 1.0};
    case SchemeKind::Usavg: return {.stress_first = true, .remap = true, .stress_last = true, .stress_dt_share = 0.5};
  }
  return {};
}

}  // namespace talus
