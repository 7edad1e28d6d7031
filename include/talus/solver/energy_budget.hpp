#pragma once
// The energy ledger: every term of a run's energy budget, named once. The solver's sums, the
// checkpoint, the energy guard, the run summary and the columns of energy.csv all go through
// EnergyBudget::for_each_term, so a new term is one member and one line there.
//
//   kinetic + strain + gravity + friction_work + plastic_work + outflow + damping = initial total
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
  }
};

}  // namespace talus
