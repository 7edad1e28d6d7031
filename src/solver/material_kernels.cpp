// Vectorised material updates, compiled once per instruction set by Highway's foreach_target and
// dispatched at run time (header: solver/material_kernels.hpp). Arithmetic only through Add, Sub,
// Mul, Div and Sqrt (correctly rounded on every target) and never MulAdd: the scalar reference has
// no fused multiply-add (the build sets -ffp-contract=off), so neither may the lanes.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "solver/material_kernels.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include <limits>

#include "talus/core/tensor.hpp"
#include "talus/solver/material_kernels.hpp"

HWY_BEFORE_NAMESPACE();
namespace talus {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using D = hn::ScalableTag<double>;
using V = hn::Vec<D>;
using Mask = hn::Mask<D>;

/// A vector of doubles with the arithmetic operators, so that the templated expressions of the
/// scalar code (rotate_objectively_values) run on it unchanged.
struct Lanes {
  V v;
  Lanes(V x) : v(x) {}  // NOLINT: implicit from a vector
  explicit Lanes(double x) : v(hn::Set(D(), x)) {}
};
inline Lanes operator+(Lanes a, Lanes b) { return hn::Add(a.v, b.v); }
inline Lanes operator-(Lanes a, Lanes b) { return hn::Sub(a.v, b.v); }
inline Lanes operator*(Lanes a, Lanes b) { return hn::Mul(a.v, b.v); }
inline Lanes operator/(Lanes a, Lanes b) { return hn::Div(a.v, b.v); }
inline Lanes operator-(Lanes a) { return hn::Neg(a.v); }

// The common part of both models: loads, the volume update V <- V (1 + tr d_eps) (Edo &
// Matsubara 2015, eq. 35) and the Hughes–Winget rotation of the stress.
struct LaneState {
  V s[6], de[6], volume;
  V trace;  // tr d_eps = (de_xx + de_yy) + de_zz, in the reference's order
};

HWY_ATTR inline LaneState load_and_rotate(const MaterialKernelFields& f, std::size_t p) {
  const D d;
  const std::size_t k = p - f.chunk_begin;
  LaneState st;
  for (int c = 0; c < 6; ++c) st.de[c] = hn::LoadU(d, f.strain_increment[c] + k);
  Lanes s[6] = {hn::LoadU(d, f.stress[0] + p), hn::LoadU(d, f.stress[1] + p), hn::LoadU(d, f.stress[2] + p),
                hn::LoadU(d, f.stress[3] + p), hn::LoadU(d, f.stress[4] + p), hn::LoadU(d, f.stress[5] + p)};
  st.trace = hn::Add(hn::Add(st.de[0], st.de[1]), st.de[2]);
  st.volume = hn::Mul(hn::LoadU(d, f.volume + p), hn::Add(hn::Set(d, 1.0), st.trace));
  rotate_objectively_values<Lanes>(s, hn::LoadU(d, f.spin[0] + k), hn::LoadU(d, f.spin[1] + k),
                                   hn::LoadU(d, f.spin[2] + k));
  for (int c = 0; c < 6; ++c) st.s[c] = s[c].v;
  return st;
}

HWY_ATTR inline void store_stress_strain_volume(const MaterialKernelFields& f, std::size_t p, const LaneState& st) {
  const D d;
  for (int c = 0; c < 6; ++c) {
    hn::StoreU(st.s[c], d, f.stress[c] + p);
    hn::StoreU(hn::Add(hn::LoadU(d, f.strain[c] + p), st.de[c]), d, f.strain[c] + p);
  }
  hn::StoreU(st.volume, d, f.volume + p);
}

// BodyMaterials' separation rule, lane by lane: beyond ratio x V0 after the volume update.
HWY_ATTR inline Mask separated_lanes(const MaterialKernelFields& f, std::size_t p, const LaneState& st, double ratio) {
  const D d;
  if (!(ratio > 0.0)) return hn::FirstN(d, 0);
  return hn::Gt(st.volume, hn::Mul(hn::Set(d, ratio), hn::LoadU(d, f.volume0 + p)));
}

// What a separated particle releases per unit volume (BodyMaterials::release_separated): the elastic
// energy density of its stress before this step's rotation, LinearElastic::energy_density's operations.
HWY_ATTR inline V separated_energy(const MaterialKernelFields& f, std::size_t p, double two_bulk, double four_shear) {
  const D d;
  V s[6];
  for (int c = 0; c < 6; ++c) s[c] = hn::LoadU(d, f.stress[c] + p);
  const V pm = hn::Div(hn::Add(hn::Add(s[0], s[1]), s[2]), hn::Set(d, 3.0));
  const V dxx = hn::Sub(s[0], pm), dyy = hn::Sub(s[1], pm), dzz = hn::Sub(s[2], pm);
  const V diagonal = hn::Add(hn::Add(hn::Mul(dxx, dxx), hn::Mul(dyy, dyy)), hn::Mul(dzz, dzz));
  const V off = hn::Add(hn::Add(hn::Mul(s[3], s[3]), hn::Mul(s[4], s[4])), hn::Mul(s[5], s[5]));
  const V contracted = hn::Add(diagonal, hn::Mul(hn::Set(d, 2.0), off));
  return hn::Add(hn::Div(hn::Mul(pm, pm), hn::Set(d, two_bulk)), hn::Div(contracted, hn::Set(d, four_shear)));
}

// The elastic trial of both plastic models: trial = sigma + 2 G d_eps, + lambda tr(d_eps) on the diagonal.
HWY_ATTR inline void elastic_trial(const LaneState& st, V two_shear, V lame, V (&trial)[6]) {
  for (int c = 0; c < 6; ++c) trial[c] = hn::Add(st.s[c], hn::Mul(two_shear, st.de[c]));
  for (int c = 0; c < 3; ++c) trial[c] = hn::Add(trial[c], hn::Mul(lame, st.trace));
}

// Adds the group's dissipation (per unit volume, times the new volume) in particle order, as the
// reference's running sum does.
HWY_ATTR inline void add_in_particle_order(V work_density, const LaneState& st, double& dissipated) {
  const D d;
  HWY_ALIGN double work[hn::MaxLanes(d)];
  hn::Store(hn::Mul(work_density, st.volume), d, work);
  for (std::size_t lane = 0; lane < hn::Lanes(d); ++lane) dissipated += work[lane];
}

HWY_ATTR KernelStop ElasticLanes(const MaterialKernelFields& f, const ElasticKernelConstants& m, std::size_t begin,
                                 std::size_t end) {
  const D d;
  const std::size_t n = hn::Lanes(d);
  const V lambda = hn::Set(d, m.lambda), two_shear = hn::Set(d, 2.0 * m.shear);
  std::size_t p = begin;
  for (; p + n <= end; p += n) {
    LaneState st = load_and_rotate(f, p);
    // LinearElastic::add_increment: s_i += lambda tr(d_eps) + 2 G d_eps_i (Edo & Matsubara 2015, eq. 34)
    const V lt = hn::Mul(lambda, st.trace);
    for (int c = 0; c < 3; ++c) st.s[c] = hn::Add(st.s[c], hn::Add(lt, hn::Mul(two_shear, st.de[c])));
    for (int c = 3; c < 6; ++c) st.s[c] = hn::Add(st.s[c], hn::Mul(two_shear, st.de[c]));
    store_stress_strain_volume(f, p, st);
  }
  return {p, end - p};
}

// DruckerPrager::plastic_return, steps 4-5, for the lanes in `rest` (outside the elastic domain and
// not returned to the cone), without a back stress (H_kin = 0: it stays +0, and the reference's
// terms with it are kept as it writes them, so every lane gets its bits): the tension cut-off
// alone, the cone/cut-off corner, or the apex. Writes those lanes of stress, eps_p and the work
// density; false where an apex lane's k_new / alpha equals the cut-off (std::fmin's choice between
// +0 and -0 is not Min's).
HWY_ATTR bool return_to_cutoff_or_apex(const DruckerPragerKernelConstants& m, Mask rest, V i1, V xi_norm, V q, V k,
                                       const V (&xi)[6],
                                       const V (&trial)[6], V (&stress)[6], V& eps_p, V& plastic_work) {
  const D d;
  const V zero = hn::Zero(d), third = hn::Set(d, 3.0), sqrt2 = hn::Set(d, 1.4142135623730951);
  const V alpha = hn::Set(d, m.alpha), hi = hn::Set(d, m.hardening_isotropic), gk = hn::Set(d, m.shear_plus_kinematic);
  const V cutoff = hn::Set(d, m.first_invariant_cutoff), three_bulk = hn::Set(d, m.three_bulk);
  // beta : xi with beta = +0, as double_contract(beta, xi) sums it
  const V beta_xi = hn::Add(hn::Add(hn::Add(hn::Mul(zero, xi[0]), hn::Mul(zero, xi[1])), hn::Mul(zero, xi[2])),
                            hn::Mul(hn::Set(d, 2.0), hn::Add(hn::Add(hn::Mul(zero, xi[3]), hn::Mul(zero, xi[4])),
                                                              hn::Mul(zero, xi[5]))));
  auto apex = rest;
  if (m.first_invariant_cutoff < std::numeric_limits<double>::infinity()) {
    // 4. Tension cut-off: I1 = 3 p_t with purely volumetric flow
    const V de_v_plastic = hn::Div(hn::Sub(i1, cutoff), three_bulk);
    const V t = hn::Sub(hn::Add(hn::Mul(alpha, cutoff), q), k);
    const auto alone = hn::And(rest, hn::Le(t, zero));
    const V shift = hn::Div(hn::Sub(cutoff, i1), third);
    const V cutoff_work = hn::Mul(hn::Div(cutoff, third), de_v_plastic);
    //    ... or at the cone/cut-off corner: dl from f = 0 on the plane, a radial return of xi
    const V dl = hn::Div(t, hn::Set(d, m.corner_denominator));
    const V q_new = hn::Sub(q, hn::Mul(gk, dl));
    const auto corner = hn::AndNot(alone, hn::And(rest, hn::Ge(q_new, zero)));
    const V scale = hn::Div(q_new, q);
    const V m_new = hn::Div(cutoff, third);
    for (int c = 0; c < 6; ++c) {
      V at_corner = hn::Add(hn::Mul(scale, xi[c]), zero);
      if (c < 3) at_corner = hn::Add(at_corner, m_new);
      const V cut = c < 3 ? hn::Add(trial[c], shift) : trial[c];
      stress[c] = hn::IfThenElse(alone, cut, hn::IfThenElse(corner, at_corner, stress[c]));
    }
    const V beta_n = hn::Div(beta_xi, hn::Mul(sqrt2, xi_norm));  // beta : n / sqrt2
    const V corner_work = hn::Add(cutoff_work, hn::Mul(dl, hn::Add(q_new, beta_n)));
    plastic_work = hn::IfThenElse(alone, cutoff_work, hn::IfThenElse(corner, corner_work, plastic_work));
    eps_p = hn::IfThenElse(corner, hn::Add(eps_p, dl), eps_p);
    apex = hn::AndNot(hn::Or(alone, corner), rest);
  }
  if (hn::AllFalse(d, apex)) return true;
  // 5. Apex: xi -> 0, dl = q / (G + H_kin), I1 = min(k_new / alpha, 3 p_t)
  const V dl = hn::Div(q, gk);
  const V k_new = hn::Add(k, hn::Mul(hi, dl));
  const V on_cone = hn::Div(k_new, alpha);
  if (!hn::AllFalse(d, hn::And(apex, hn::Eq(on_cone, cutoff)))) return false;
  const V i1_new = hn::Min(on_cone, cutoff);
  const V de_v_plastic = hn::Div(hn::Sub(i1, i1_new), three_bulk);
  const V m_new = hn::Div(i1_new, third);
  for (int c = 0; c < 6; ++c) stress[c] = hn::IfThenElse(apex, c < 3 ? hn::Add(zero, m_new) : zero, stress[c]);
  const V apex_work = hn::Add(hn::Mul(m_new, de_v_plastic), hn::Div(beta_xi, hn::Set(d, m.two_shear_plus_kinematic)));
  plastic_work = hn::IfThenElse(apex, apex_work, plastic_work);
  eps_p = hn::IfThenElse(apex, hn::Add(eps_p, dl), eps_p);
  return true;
}

HWY_ATTR KernelStop DruckerPragerLanes(const MaterialKernelFields& f, const DruckerPragerKernelConstants& m,
                                       std::size_t begin, std::size_t end, double& dissipated) {
  const D d;
  const std::size_t n = hn::Lanes(d);
  const V zero = hn::Zero(d), two_shear = hn::Set(d, 2.0 * m.shear), lame = hn::Set(d, m.lame);
  const V third = hn::Set(d, 3.0), two = hn::Set(d, 2.0), sqrt2 = hn::Set(d, 1.4142135623730951);
  const V alpha = hn::Set(d, m.alpha), k0 = hn::Set(d, m.initial_strength), hi = hn::Set(d, m.hardening_isotropic);
  const V gk = hn::Set(d, m.shear_plus_kinematic), cutoff = hn::Set(d, m.first_invariant_cutoff);
  const V flowing_strain = hn::Set(d, m.flowing_plastic_strain);
  std::size_t p = begin;
  for (; p + n <= end; p += n) {
    LaneState st = load_and_rotate(f, p);
    // A separated lane keeps none of what follows: no stress, no plastic strain, and its stored
    // energy released (BodyMaterials::release_separated).
    const auto separated = separated_lanes(f, p, st, m.separation_volume_ratio);
    const bool any_separated = !hn::AllFalse(d, separated);
    const V released = any_separated ? separated_energy(f, p, m.separated_two_bulk, m.separated_four_shear) : zero;
    const V eps_p = hn::LoadU(d, f.plastic_strain + p);
    // Abe, Johansson & Konagai 2005, sec. 7: the flowing model (psi = flowing value) once eps_p is past the threshold.
    const auto flowing = hn::Gt(eps_p, flowing_strain);
    const V cone_denominator = hn::IfThenElse(flowing, hn::Set(d, m.cone_denominator[1]), hn::Set(d, m.cone_denominator[0]));
    const V dilation = hn::IfThenElse(flowing, hn::Set(d, m.dilation_factor[1]), hn::Set(d, m.dilation_factor[0]));
    const V alpha_excess = hn::IfThenElse(flowing, hn::Set(d, m.alpha_excess[1]), hn::Set(d, m.alpha_excess[0]));
    // DruckerPrager::update, step 1: elastic trial.
    V trial[6];
    elastic_trial(st, two_shear, lame, trial);
    // Step 2: invariants (the back stress is zero) and the yield function, Abe, Johansson & Konagai 2005, eq. 23.
    const V i1 = hn::Add(hn::Add(trial[0], trial[1]), trial[2]);
    const V mean = hn::Div(i1, third);
    V xi[6];
    for (int c = 0; c < 3; ++c) xi[c] = hn::Sub(trial[c], mean);
    for (int c = 3; c < 6; ++c) xi[c] = trial[c];
    const V diagonal = hn::Add(hn::Add(hn::Mul(xi[0], xi[0]), hn::Mul(xi[1], xi[1])), hn::Mul(xi[2], xi[2]));
    const V shear = hn::Add(hn::Add(hn::Mul(xi[3], xi[3]), hn::Mul(xi[4], xi[4])), hn::Mul(xi[5], xi[5]));
    const V xi_norm = hn::Sqrt(hn::Add(diagonal, hn::Mul(two, shear)));
    const V q = hn::Div(xi_norm, sqrt2);
    const V k = hn::Add(k0, hn::Mul(hi, eps_p));
    const V fy = hn::Sub(hn::Add(hn::Mul(alpha, i1), q), k);
    const auto elastic = hn::And(hn::Le(fy, zero), hn::Le(i1, cutoff));
    // Step 3: return to the cone, f linear in the multiplier dl.
    const V dl = hn::Div(fy, cone_denominator);
    const V q_new = hn::Sub(q, hn::Mul(gk, dl));
    const V i1_new = hn::Sub(i1, hn::Mul(dilation, dl));
    const auto cone = hn::And(hn::And(hn::Gt(fy, zero), hn::Ge(q_new, zero)), hn::Le(i1_new, cutoff));
    if (!hn::AllTrue(d, hn::Or(hn::IsFinite(fy), separated))) return {p, n};  // a non-finite input: reference
    const V scale = hn::Div(q_new, q);
    const V m_new = hn::Div(i1_new, third);
    V stress[6];
    for (int c = 0; c < 6; ++c) {
      V returned = hn::Add(hn::Mul(scale, xi[c]), zero);  // + the (zero) back stress, as the reference adds it
      if (c < 3) returned = hn::Add(returned, m_new);
      stress[c] = hn::IfThenElse(cone, returned, trial[c]);
    }
    // sigma : d_eps^p = dl (k_new - (alpha - alpha_g) I1_new), clamped at +0 (DruckerPrager::plastic_return)
    const V bracket = hn::Sub(hn::Add(k, hn::Mul(hi, dl)), hn::Mul(alpha_excess, i1_new));
    V plastic_work = hn::IfThenElseZero(cone, hn::Mul(dl, hn::IfThenElse(hn::Gt(bracket, zero), bracket, zero)));
    V eps_new = hn::IfThenElse(cone, hn::Add(eps_p, dl), eps_p);
    const auto rest = hn::AndNot(separated, hn::Not(hn::Or(elastic, cone)));
    if (!hn::AllFalse(d, rest) &&
        !return_to_cutoff_or_apex(m, rest, i1, xi_norm, q, k, xi, trial, stress, eps_new, plastic_work))
      return {p, n};  // a tie the reference's fmin may break otherwise: reference
    for (int c = 0; c < 6; ++c) st.s[c] = hn::IfThenZeroElse(separated, stress[c]);
    if (any_separated) {
      eps_new = hn::IfThenZeroElse(separated, eps_new);
      plastic_work = hn::IfThenElse(separated, released, plastic_work);
    }
    hn::StoreU(eps_new, d, f.plastic_strain + p);
    store_stress_strain_volume(f, p, st);
    add_in_particle_order(plastic_work, st, dissipated);
  }
  return {p, end - p};
}

HWY_ATTR KernelStop MuILanes(const MaterialKernelFields& f, const MuIKernelConstants& m, std::size_t begin,
                             std::size_t end, double& dissipated) {
  const D d;
  const std::size_t n = hn::Lanes(d);
  const V zero = hn::Zero(d), half = hn::Set(d, 0.5), two = hn::Set(d, 2.0), third = hn::Set(d, 3.0);
  const V two_shear = hn::Set(d, 2.0 * m.shear), lame = hn::Set(d, m.lame), shear = hn::Set(d, m.shear);
  const V mu_s = hn::Set(d, m.mu_s), mu_2 = hn::Set(d, m.mu_2), i0 = hn::Set(d, m.i0), rise = hn::Set(d, m.friction_rise);
  const V rate_constant = hn::Set(d, m.rate_constant), dt = hn::Set(d, m.dt), mu_s_i0 = hn::Set(d, m.mu_s * m.i0);
  const V i0_squared = hn::Set(d, m.i0 * m.i0);
  const V one = hn::Set(d, 1.0), bulk = hn::Set(d, m.bulk);
  std::size_t p = begin;
  for (; p + n <= end; p += n) {
    LaneState st = load_and_rotate(f, p);
    const auto separated = separated_lanes(f, p, st, m.separation_volume_ratio);  // as in DruckerPragerLanes
    const bool any_separated = !hn::AllFalse(d, separated);
    const V released_separated =
        any_separated ? separated_energy(f, p, m.separated_two_bulk, m.separated_four_shear) : zero;
    // MuI::update, step 1: elastic trial, pressure and deviator.
    V trial[6], s[6];
    elastic_trial(st, two_shear, lame, trial);
    const V mean = hn::Div(hn::Add(hn::Add(trial[0], trial[1]), trial[2]), third);
    const V pressure = hn::Neg(mean);
    // Step 2, disconnected (no contact pressure): no stress, and the work E(sigma_n) + sigma_n : d_eps
    // released (none where it is below zero), in MuI::update's operations (MuI::elastic_energy_density, then the work in component
    // order). A free surface puts a few such particles in many groups; the steps below give such a
    // lane values it does not keep (a square root of a negative pressure: NaN, selected away).
    const auto connected = hn::Gt(pressure, zero);
    V released = zero;
    if (!hn::AllTrue(d, connected)) {
      const V m3 = hn::Div(hn::Add(hn::Add(st.s[0], st.s[1]), st.s[2]), third);
      const V dxx = hn::Sub(st.s[0], m3), dyy = hn::Sub(st.s[1], m3), dzz = hn::Sub(st.s[2], m3);
      V tau2 = hn::Mul(half, hn::Add(hn::Add(hn::Mul(dxx, dxx), hn::Mul(dyy, dyy)), hn::Mul(dzz, dzz)));
      for (int c = 3; c < 6; ++c) tau2 = hn::Add(tau2, hn::Mul(st.s[c], st.s[c]));
      const V energy = hn::Mul(half, hn::Add(hn::Div(hn::Mul(m3, m3), bulk), hn::Div(tau2, shear)));
      V work = zero;
      for (int c = 0; c < 6; ++c) work = hn::Add(work, hn::Mul(hn::Mul(c < 3 ? one : two, st.s[c]), st.de[c]));
      released = hn::Add(energy, work);
      released = hn::IfThenElse(hn::Lt(released, zero), zero, released);  // MuI::update's "released < 0 ? 0"
    }
    for (int c = 0; c < 3; ++c) s[c] = hn::Sub(trial[c], mean);
    for (int c = 3; c < 6; ++c) s[c] = trial[c];
    const V normal = hn::Add(hn::Add(hn::Mul(s[0], s[0]), hn::Mul(s[1], s[1])), hn::Mul(s[2], s[2]));
    const V tau_trial = hn::Sqrt(hn::Add(hn::Add(hn::Add(hn::Mul(half, normal), hn::Mul(s[3], s[3])), hn::Mul(s[4], s[4])),
                                         hn::Mul(s[5], s[5])));
    // Step 3: below the static yield cone, elastic. Step 4: flowing, the smaller root of the
    // quadratic in mu (Jop et al. 2006; docs/mu-i.md).
    const auto flowing = hn::Not(hn::Le(tau_trial, hn::Mul(mu_s, pressure)));
    const V ratio = hn::Div(tau_trial, pressure);
    const V big_b = hn::Div(hn::Mul(rate_constant, hn::Sqrt(pressure)), dt);
    const V b = hn::Add(hn::Mul(big_b, hn::Add(ratio, mu_2)), i0);
    const V c = hn::Add(hn::Mul(hn::Mul(big_b, ratio), mu_2), mu_s_i0);
    const V gap = hn::Sub(ratio, mu_2);
    const V disc = hn::Add(hn::Add(hn::Mul(hn::Mul(hn::Mul(big_b, big_b), gap), gap),
                                   hn::Mul(hn::Mul(hn::Mul(two, big_b), i0), hn::Add(hn::Sub(ratio, mu_s), rise))),
                           i0_squared);
    const V mu = hn::Div(hn::Mul(two, c), hn::Add(b, hn::Sqrt(disc)));
    const V tau = hn::Mul(mu, pressure);
    const V scale = hn::Div(mu, ratio);
    for (int k = 0; k < 6; ++k) {
      const V returned = hn::Add(hn::Mul(scale, s[k]), k < 3 ? mean : zero);
      st.s[k] = hn::IfThenElseZero(connected, hn::IfThenElse(flowing, returned, trial[k]));
    }
    const auto yielding = hn::And(connected, flowing);
    const V plastic_shear_strain = hn::IfThenElseZero(yielding, hn::Div(hn::Sub(tau_trial, tau), shear));
    V plastic_work = hn::IfThenElse(connected, hn::IfThenElseZero(flowing, hn::Mul(tau, plastic_shear_strain)),
                                    released);
    V eps_new = hn::Add(hn::LoadU(d, f.plastic_strain + p), plastic_shear_strain);
    if (any_separated) {
      for (int k = 0; k < 6; ++k) st.s[k] = hn::IfThenZeroElse(separated, st.s[k]);
      eps_new = hn::IfThenZeroElse(separated, eps_new);
      plastic_work = hn::IfThenElse(separated, released_separated, plastic_work);
    }
    hn::StoreU(eps_new, d, f.plastic_strain + p);
    store_stress_strain_volume(f, p, st);
    add_in_particle_order(plastic_work, st, dissipated);
  }
  return {p, end - p};
}

}  // namespace HWY_NAMESPACE
}  // namespace talus
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace talus {

HWY_EXPORT(ElasticLanes);
HWY_EXPORT(DruckerPragerLanes);
HWY_EXPORT(MuILanes);

KernelStop update_elastic_lanes(const MaterialKernelFields& fields, const ElasticKernelConstants& constants,
                                std::size_t begin, std::size_t end) {
  return HWY_DYNAMIC_DISPATCH(ElasticLanes)(fields, constants, begin, end);
}

KernelStop update_drucker_prager_lanes(const MaterialKernelFields& fields,
                                       const DruckerPragerKernelConstants& constants, std::size_t begin,
                                       std::size_t end, double& dissipated) {
  return HWY_DYNAMIC_DISPATCH(DruckerPragerLanes)(fields, constants, begin, end, dissipated);
}

KernelStop update_mu_i_lanes(const MaterialKernelFields& fields, const MuIKernelConstants& constants, std::size_t begin,
                             std::size_t end, double& dissipated) {
  return HWY_DYNAMIC_DISPATCH(MuILanes)(fields, constants, begin, end, dissipated);
}

}  // namespace talus
#endif
