#pragma once
// The energy ledger: every term of a run's energy budget, named once. The solver's sums, the
// checkpoint, the energy guard, the run summary and the columns of energy.csv all go through
// EnergyBudget::for_each_term, so a new term is one member and one line there.
//
//   kinetic + strain + gravity + friction_work + plastic_work + outflow + damping + gravity_ramp
//     = initial total
//
// For a conservative continuum the total stays at its initial value; its drift measures the
// scheme's numerical dissipation or gain (and the energy lost in no-rebound impacts on walls, which
// a rigid wall's normal impulse does not account for).
namespace talus {

struct EnergyBudget {
  // Functions of the particles' state, summed anew whenever they are asked for (Solver::energies).
  double kinetic = 0.0;
  double strain = 0.0;          // stored elastic energy
  double gravity = 0.0;         // -sum m g.x (zero at the grid origin)
  // Work done, accumulated step by step: a checkpoint must carry these.
  double friction_work = 0.0;   // dissipated by wall friction
  double plastic_work = 0.0;    // dissipated by the material (plastic work, separation)
  double outflow = 0.0;         // energy (kinetic + strain + gravity) carried out through open faces
  double damping = 0.0;         // kinetic energy removed by the PIC share of G2P (solver.pic_fraction)
  /// While gravity ramps (solver.gravity_ramp_time), `gravity` (the full g's potential) falls faster
  /// than the ramped gravity works: the potential released that it did not turn into work, (1 - t /
  /// ramp time) of each step's release. Zero without a ramp and constant after it.
  double gravity_ramp = 0.0;

  /// Sum of every term, in ledger order.
  double total() const {
    double sum = 0.0;
    for_each_term(*this, [&](const char*, double value, bool) { sum += value; });
    return sum;
  }

  /// Visit every term of `e` (const or not) in ledger order: f(const char* name, double& value,
  /// bool accumulated). The name is the term's energy.csv column and checkpoint attribute;
  /// `accumulated` marks work done.
  template <class Budget, class F>
  static void for_each_term(Budget& e, F&& f) {
    f("kinetic", e.kinetic, false);
    f("strain", e.strain, false);
    f("gravity", e.gravity, false);
    f("friction_work", e.friction_work, true);
    f("plastic_work", e.plastic_work, true);
    f("outflow", e.outflow, true);
    f("damping", e.damping, true);
    f("gravity_ramp", e.gravity_ramp, true);
  }
};

/// What the budget's gap is made of (`output.energy_gap_terms`; docs/theory.md "Where the budget's
/// gap comes from"). Not terms of the ledger: each is a work done on the grid's motion, to be
/// compared with the ledger's own count of it, plus the kinetic energy lost between grid and
/// particles. Per step and node, with v the node's velocity at the start and v^L at the end (walls
/// applied) and v_mean = (v + v^L) / 2, the grid's kinetic energy changes by
/// 1/2 m (|v^L|^2 - |v|^2) = dt f . v_mean + dt m g . v_mean + (the walls' share, the rest).
/// The particles' kinetic energy changes by the same minus `transfer_loss` (and the PIC damping, and
/// the kinetic energy of the particles removed at open faces), so
///   total - initial total = (strain change + outflow_strain + plastic_work - grid_stress_work)
///                         + (friction_work - grid_wall_work)
///                         + (gravity change + gravity_ramp + outflow_gravity + grid_gravity_work)
///                         - transfer_loss
/// to round-off (outflow_strain, outflow_gravity: the stored and potential energy the removed
/// particles took with them, parts of the ledger's `outflow`, which the strain and gravity changes
/// miss).
struct EnergyGapTerms {
  double grid_stress_work = 0.0;   // -sum dt f_int . v_mean: the internal forces' work against the grid's motion
  double grid_wall_work = 0.0;     // kinetic energy the walls' impulses take from the grid's motion
  double grid_gravity_work = 0.0;  // sum dt m g . v_mean: gravity's work on the grid's motion
  /// sum_I 1/2 m_I |dv_I|^2 - sum_p 1/2 m_p |sum_I N_Ip dv_I|^2 >= 0 (Jensen's inequality), dv_I =
  /// v^L - v: the kinetic energy of the nodes' velocity increments that the particles' FLIP update
  /// does not take up (Edo & Matsubara 2015, eq. 50).
  double transfer_loss = 0.0;
  double outflow_strain = 0.0;   // the stored (strain) part of the ledger's `outflow`
  double outflow_gravity = 0.0;  // the potential part of the ledger's `outflow`

  /// Visit every term (const or not) in column order: f(const char* name, double& value).
  template <class Terms, class F>
  static void for_each_term(Terms& t, F&& f) {
    f("grid_stress_work", t.grid_stress_work);
    f("grid_wall_work", t.grid_wall_work);
    f("grid_gravity_work", t.grid_gravity_work);
    f("transfer_loss", t.transfer_loss);
    f("outflow_strain", t.outflow_strain);
    f("outflow_gravity", t.outflow_gravity);
  }
};

/// The gap's parts by the identity above, whose sum is total - initial total to round-off:
/// `initial` the ledger at the start, `now` and `terms` at the same later time.
struct EnergyGapParts {
  double stress = 0.0;    // strain change + outflow_strain + plastic_work - grid_stress_work
  double walls = 0.0;     // friction_work - grid_wall_work
  double gravity = 0.0;   // gravity change + gravity_ramp + outflow_gravity + grid_gravity_work
  double transfer = 0.0;  // -transfer_loss
  double sum() const { return stress + walls + gravity + transfer; }
};

inline EnergyGapParts energy_gap_parts(const EnergyBudget& initial, const EnergyBudget& now, const EnergyGapTerms& t) {
  return {.stress = now.strain - initial.strain + t.outflow_strain + now.plastic_work - initial.plastic_work -
                    t.grid_stress_work,
          .walls = now.friction_work - initial.friction_work - t.grid_wall_work,
          .gravity = now.gravity - initial.gravity + now.gravity_ramp - initial.gravity_ramp + t.outflow_gravity +
                     t.grid_gravity_work,
          .transfer = -t.transfer_loss};
}

}  // namespace talus
