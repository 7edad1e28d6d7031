// Single-point driver for the Drucker–Prager model (Abe, Johansson & Konagai 2005, sec. 6(3), Fig. 13).
#include "talus/material/element_test.hpp"

#include "talus/core/error.hpp"
#include "talus/core/tensor.hpp"

#include <Eigen/Dense>
#include <fmt/core.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <ostream>
#include <string>

namespace talus {

namespace {

using SmallVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 6, 1>;
using SmallMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;

// Which strain component the path drives and which stress components it holds.
struct Control {
  int driven = YY;
  double factor = -1.0;  // d_eps[driven] = factor * d(control strain)
  std::array<int, 6> held{};
  int held_count = 0;
  double held_stress = 0.0;  // value of every held stress component
  bool spin = false;
};

Control control_for(const ElementTestSpec& spec) {
  Control c;
  switch (spec.path) {
    case ElementPath::UniaxialCompression:
    case ElementPath::DrainedTriaxial:
      c.driven = YY;
      c.factor = -1.0;  // axial shortening
      c.held = {XX, ZZ};
      c.held_count = 2;
      c.held_stress = -spec.pressure;
      break;
    case ElementPath::Oedometer:
      c.driven = YY;
      c.factor = -1.0;
      break;
    case ElementPath::SimpleShear:
      c.driven = XY;
      c.factor = 0.5;  // tensor eps_xy = gamma_xy / 2
      c.held = {YY};
      c.held_count = 1;
      c.held_stress = -spec.pressure;
      c.spin = spec.spin;
      break;
  }
  return c;
}

/// The held strain increments that keep the held stresses where they are if the increment is
/// elastic (isotropic: sigma = lambda tr(eps) I + 2 G eps, tensor shears), given the driven one.
SmallVector elastic_held_strains(const Control& control, const Sym6& d_eps, const DruckerPragerParameters& material) {
  const ElasticModuli moduli = material.moduli();
  const double shear = moduli.shear(), lame = moduli.lame();
  const auto stiffness = [&](int i, int j) {  // d sigma_i / d eps_j
    return (i < 3 && j < 3 ? lame : 0.0) + (i == j ? 2.0 * shear : 0.0);
  };
  const int m = control.held_count;
  SmallMatrix held(m, m);
  SmallVector load(m);
  for (int a = 0; a < m; ++a) {
    for (int b = 0; b < m; ++b) held(a, b) = stiffness(control.held[a], control.held[b]);
    load[a] = -stiffness(control.held[a], control.driven) * d_eps[control.driven];
  }
  return held.fullPivLu().solve(load);
}

/// The held strain increments of a purely volumetric increment (every normal strain equal to the driven
/// one, no shear): the answer where the stress sits at the tension cut-off with no deviator, which
/// Newton cannot find from the cut-off/cone corner (the corner's held stresses do not change along
/// the deviator's length, so the tangent is singular there). Zero for a driven shear.
SmallVector volumetric_held_strains(const Control& control, const Sym6& d_eps) {
  SmallVector u = SmallVector::Zero(control.held_count);
  if (control.driven < 3)
    for (int a = 0; a < control.held_count; ++a)
      if (control.held[a] < 3) u[a] = d_eps[control.driven];
  return u;
}

/// The largest held strain increment, as a multiple of the driven one, that an increment's answer
/// may have. Elastic, cone, apex and cut-off answers stay within a few times the driven increment
/// (lateral over axial: nu for elasticity, at most 2 on the cone with psi <= phi, 1 at the cut-off).
/// A Newton step that left this reach followed a tangent that was nearly singular (the corner
/// above) and, at uniaxial extension onto a cut-off of 0, ended where the held strains were 1e17
/// and the stress rounded to exactly 0: a "converged" row of nonsense whose size depended on the
/// number of increments.
constexpr double kHeldStrainReach = 100.0;

}  // namespace

const char* regime_name(DruckerPragerResult::Regime regime) {
  switch (regime) {
    case DruckerPragerResult::Regime::Elastic: return "elastic";
    case DruckerPragerResult::Regime::Cone: return "cone";
    case DruckerPragerResult::Regime::Apex: return "apex";
    case DruckerPragerResult::Regime::TensionCutoff: return "tension_cutoff";
  }
  return "unknown";
}

std::vector<ElementTestPoint> run_element_test(const ElementTestSpec& spec) {
  const DruckerPrager model(spec.material, "material.");
  const Control control = control_for(spec);

  // Split the increments among the legs in proportion to their length.
  std::vector<double> targets{0.0};
  targets.insert(targets.end(), spec.strain_targets.begin(), spec.strain_targets.end());
  double total_length = 0.0;
  for (std::size_t i = 1; i < targets.size(); ++i) total_length += std::abs(targets[i] - targets[i - 1]);
  if (!(total_length > 0.0) || spec.increments < 1)
    throw input_error("path: the strain targets must move away from 0 and increments must be >= 1");

  std::vector<ElementTestPoint> points;
  ElementTestPoint point;
  point.stress = -spec.pressure * identity6();
  DruckerPragerState state;
  point.yield_function = model.yield_function(point.stress, state);
  points.push_back(point);

  const int m = control.held_count;
  SmallVector unknown = SmallVector::Zero(m);  // held-component strain increments (Newton guess)
  int step = 0;
  double walked = 0.0;  // path length before this leg
  for (std::size_t leg = 1; leg < targets.size(); ++leg) {
    const double length = targets[leg] - targets[leg - 1];
    if (length == 0.0) continue;
    // Round the cumulative share, not each leg's: the legs then add up to exactly `increments`
    // (rounding each leg gave one extra for two legs of 1.5 increments each). A leg gets at least one.
    const auto share = [&](double l) { return std::lround(spec.increments * l / total_length); };
    const int n = std::max(1, static_cast<int>(share(walked + std::abs(length)) - share(walked)));
    walked += std::abs(length);
    const double d_control = length / n;
    for (int i = 0; i < n; ++i) {
      ++step;
      Sym6 d_eps = Sym6::Zero();
      d_eps[control.driven] = control.factor * d_control;

      // Objective update: rotate stress and state to the end of the step, then update.
      Sym6 stress_n = point.stress;
      DruckerPragerState state_n = state;
      if (control.spin) {
        const double w_xy = 0.5 * d_control;  // v_x = gamma_dot y: W_xy = gamma_dot / 2
        rotate_objectively(stress_n, 0.0, 0.0, w_xy);
        model.rotate_state(state_n, 0.0, 0.0, w_xy);
      }

      Sym6 stress;
      DruckerPragerState trial_state;
      DruckerPragerResult result;
      auto evaluate = [&](const SmallVector& u, SmallVector& residual) {
        Sym6 e = d_eps;
        for (int j = 0; j < m; ++j) e[control.held[j]] = u[j];
        stress = stress_n;
        trial_state = state_n;
        result = model.update(stress, trial_state, e);
        residual.resize(m);
        for (int j = 0; j < m; ++j) residual[j] = stress[control.held[j]] - control.held_stress;
      };

      const double scale =
          std::max({stress_n.cwiseAbs().maxCoeff(), spec.pressure, model.initial_strength(),
                    spec.material.young * std::abs(d_eps[control.driven])});
      const double tolerance = 1e-12 * scale;
      const double reach = kHeldStrainReach * std::abs(d_eps[control.driven]);
      SmallVector residual;
      double farthest = 0.0;  // the largest held strain a refused answer had (for the message)
      // Newton on the held strains from `start`; false when 50 iterations do not converge, or when
      // the answer lies beyond the reach (each step is shortened to it; see kHeldStrainReach).
      auto solve_from = [&](const SmallVector& start) {
        unknown = start;
        evaluate(unknown, residual);
        for (int iteration = 0; m > 0 && residual.cwiseAbs().maxCoeff() > tolerance; ++iteration) {
          if (iteration == 50) return false;
          // Algorithmic tangent d sigma_held / d eps_held by forward differences of update().
          const double h = 1e-7 * std::max({std::abs(d_eps[control.driven]), unknown.cwiseAbs().maxCoeff(), 1e-12});
          SmallMatrix jacobian(m, m);
          SmallVector shifted_residual;
          for (int j = 0; j < m; ++j) {
            SmallVector u = unknown;
            u[j] += h;
            evaluate(u, shifted_residual);
            jacobian.col(j) = (shifted_residual - residual) / h;
          }
          SmallVector newton_step = jacobian.fullPivLu().solve(-residual);
          const double length = newton_step.cwiseAbs().maxCoeff();
          if (!(length <= reach)) newton_step *= reach / length;  // (a NaN step: zero, and no progress)
          if (!newton_step.allFinite()) newton_step.setZero();
          // Backtracking: halve the step until the residual decreases (guards against kinks
          // between regimes inside one increment).
          double t = 1.0;
          const double r0 = residual.norm();
          SmallVector candidate_residual;
          SmallVector candidate;
          for (int halving = 0; halving < 30; ++halving, t *= 0.5) {
            candidate = unknown + t * newton_step;
            evaluate(candidate, candidate_residual);
            if (candidate_residual.norm() < r0) break;
          }
          unknown = candidate;
          residual = candidate_residual;
        }
        const double size = m > 0 ? unknown.cwiseAbs().maxCoeff() : 0.0;
        if (size <= reach) return true;
        farthest = std::max(farthest, size);
        return false;
      };
      // The previous increment's held strains, which a monotonic path continues. At a reversal they
      // point the wrong way: an unloading step started from the loading's lateral expansion landed at
      // the apex, where the tangent is zero, and failed although its answer is elastic. Then the
      // elastic answer, zero, and the volumetric answer of the cut-off (volumetric_held_strains).
      const SmallVector previous = unknown;
      if (!solve_from(previous) && !solve_from(elastic_held_strains(control, d_eps, spec.material)) &&
          !solve_from(SmallVector::Zero(m)) && !solve_from(volumetric_held_strains(control, d_eps))) {
        if (farthest > 0.0)
          throw instability_error(fmt::format(
              "element test: mixed control found no bounded answer at increment {}: the held strains ran to {:.6g}, "
              "more than {} times the driven strain increment {:.6g} (a nearly singular tangent, as at the tension "
              "cut-off's corner); no row is trustworthy from here; more increments (path.increments = {}) make each "
              "step smaller",
              step, farthest, kHeldStrainReach, std::abs(d_eps[control.driven]), spec.increments));
        evaluate(previous, residual);
        throw instability_error(fmt::format(
            "element test: mixed control did not converge at increment {} (held-stress residual {:.6g} Pa from the "
            "previous increment's strains); more increments (path.increments = {}) make each step smaller",
            step, residual.cwiseAbs().maxCoeff(), spec.increments));
      }

      state = trial_state;
      point.step = step;
      for (int j = 0; j < m; ++j) d_eps[control.held[j]] = unknown[j];
      point.strain += d_eps;
      point.stress = stress;
      point.equivalent_plastic_strain = state.equivalent_plastic_strain;
      point.back_stress = state.back_stress;
      point.yield_function = model.yield_function(stress, state);
      point.regime = result.regime;
      point.plastic_work += result.plastic_work;
      points.push_back(point);
    }
  }
  return points;
}

void write_element_test_csv(std::ostream& out, const std::vector<ElementTestPoint>& points) {
  out << "step,eps_xx,eps_yy,eps_zz,eps_yz,eps_xz,eps_xy,sig_xx,sig_yy,sig_zz,sig_yz,sig_xz,sig_xy,"
         "eps_v,gamma_xy,eps_q,p,q,eq_plastic_strain,yield_function,regime,plastic_work\n";
  char buffer[64];
  auto put = [&](double v) {
    std::snprintf(buffer, sizeof buffer, ",%.15g", v + 0.0);  // (+ 0.0: the start's shears read "-0")
    out << buffer;
  };
  for (const ElementTestPoint& pt : points) {
    out << pt.step;
    for (int i = 0; i < 6; ++i) put(pt.strain[i]);
    for (int i = 0; i < 6; ++i) put(pt.stress[i]);
    const Sym6 e = deviator(pt.strain);
    put(trace(pt.strain));                                // eps_v, expansion positive
    put(2.0 * pt.strain[XY]);                             // engineering gamma_xy
    put(std::sqrt(2.0 / 3.0 * double_contract(e, e)));    // eps_q
    put(-trace(pt.stress) / 3.0);                         // p, compression positive
    put(std::sqrt(3.0 * j2(pt.stress)));                  // q (von Mises)
    put(pt.equivalent_plastic_strain);
    put(pt.yield_function);
    out << ',' << regime_name(pt.regime);
    put(pt.plastic_work);
    out << '\n';
  }
}

}  // namespace talus
