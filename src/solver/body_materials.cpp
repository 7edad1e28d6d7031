#include "talus/solver/body_materials.hpp"

#include "talus/core/simd_dispatch.hpp"
#include "talus/core/tensor.hpp"

#include <algorithm>

namespace talus {

namespace {

DruckerPragerKernelConstants lane_constants(const std::vector<DruckerPrager>& models, const GranularOptions& granular,
                                            const LinearElastic& elastic) {
  DruckerPragerKernelConstants c;
  const DruckerPrager& m = models[0];  // [1] differs only in alpha_g
  c.shear = m.shear_modulus();
  c.lame = m.lame_lambda();
  c.alpha = m.alpha();
  c.initial_strength = m.initial_strength();
  c.hardening_isotropic = m.hardening_isotropic();
  c.shear_plus_kinematic = m.shear_modulus() + m.hardening_kinematic();
  c.first_invariant_cutoff = m.first_invariant_cutoff();
  const double g = m.shear_modulus(), hk = m.hardening_kinematic(), hi = m.hardening_isotropic();
  c.three_bulk = 3.0 * m.bulk_modulus();
  c.corner_denominator = g + hk + hi;
  c.two_shear_plus_kinematic = 2.0 * (g + hk);
  c.separation_volume_ratio = granular.separation_volume_ratio;
  // release_separated's LinearElastic::energy_density: p^2 / (2 K) + dev:dev / (4 G)
  c.separated_two_bulk = 2.0 * elastic.bulk();
  c.separated_four_shear = 4.0 * elastic.shear;
  c.flowing_plastic_strain = granular.flowing_plastic_strain;
  for (int i = 0; i < 2; ++i) {
    c.cone_denominator[i] = models[i].cone_denominator();
    c.dilation_factor[i] = 9.0 * models[i].bulk_modulus() * models[i].alpha_dilatancy();
    c.alpha_excess[i] = models[i].alpha() - models[i].alpha_dilatancy();
  }
  return c;
}

MuIKernelConstants lane_constants(const MuI& model, const GranularOptions& granular, const LinearElastic& elastic) {
  MuIKernelConstants c;
  c.shear = model.shear_modulus();
  c.lame = model.lame_lambda();
  c.bulk = model.bulk_modulus();
  c.mu_s = model.parameters().mu_s;
  c.mu_2 = model.parameters().mu_2;
  c.i0 = model.parameters().i0;
  c.friction_rise = model.friction_rise();
  c.rate_constant = model.rate_constant();
  c.separation_volume_ratio = granular.separation_volume_ratio;
  // release_separated's LinearElastic::energy_density: p^2 / (2 K) + dev:dev / (4 G)
  c.separated_two_bulk = 2.0 * elastic.bulk();
  c.separated_four_shear = 4.0 * elastic.shear;
  return c;
}

}  // namespace

BodyMaterials::BodyMaterials(const Scene& scene, ParticleStore& particles) {
  for (const BodySpec& b : scene.bodies) {
    const MaterialSpec& m = scene.materials[b.material];
    Body body;
    body.model = m.model;
    body.elastic = LinearElastic::from_moduli(m.elastic);
    body.p_wave_modulus = m.elastic.p_wave();
    if (m.model == MaterialModel::DruckerPrager) {
      const std::string prefix = "materials." + m.name + ".";
      body.plastic.emplace_back(m.drucker_prager, prefix);
      body.plastic.push_back(body.plastic[0].with_dilatancy(m.granular.flowing_dilatancy_angle_deg));
      body.granular = m.granular;
      body.drucker_prager_lanes = lane_constants(body.plastic, body.granular, body.elastic);
      any_plastic_ = true;
      // the back stress moves only with kinematic hardening (docs/drucker-prager.md)
      any_kinematic_ = any_kinematic_ || (m.drucker_prager.hardening_modulus > 0.0 && m.drucker_prager.kinematic_fraction > 0.0);
    } else if (m.model == MaterialModel::MuI) {
      body.mu_i.emplace_back(m.mu_i, "materials." + m.name + ".");
      body.granular = m.granular;  // the separation rule only
      body.mu_i_lanes = lane_constants(body.mu_i[0], body.granular, body.elastic);
      any_plastic_ = true;         // the equivalent plastic shear strain is kept per particle
    }
    bodies_.push_back(std::move(body));
  }
  if (any_plastic_ && !particles.has_plastic_state()) particles.enable_plastic_state(any_kinematic_);
}

// Separated: no contact with neighbours, hence no stress (the rule of both granular models).
[[gnu::always_inline]] inline bool BodyMaterials::separated(const Body& body, const ParticleStore& P, std::size_t p) {
  const double ratio = body.granular.separation_volume_ratio;
  return ratio > 0.0 && P.volume[p] > ratio * P.volume0[p];
}

// The elastic energy a separated particle still held is released without doing work on the
// continuum; count it as dissipated so the budget closes. Resets the plastic state, zeroes s.
[[gnu::always_inline]] inline double BodyMaterials::release_separated(const Body& body, ParticleStore& P, std::size_t p,
                                                                      Sym6& s) {
  const double released = P.volume[p] * body.elastic.energy_density(s);
  P.plastic_strain[p] = 0.0;
  if (P.has_back_stress())
    for (int c = 0; c < 6; ++c) P.back_stress[c][p] = 0.0;
  s.setZero();
  return released;
}

// Inlined into update(): as a call, the stress passed through memory cost a stalled reload
// (store forwarding) that perf put at 7% of a B-spline Drucker-Prager step.
[[gnu::always_inline]] inline double BodyMaterials::update_drucker_prager(const Body& body, ParticleStore& P, std::size_t p, Sym6& s,
                                            const Sym6& de, double w_yz, double w_xz, double w_xy) const {
  if (separated(body, P, p)) return release_separated(body, P, p, s);
  DruckerPragerState state;
  state.equivalent_plastic_strain = P.plastic_strain[p];
  const bool kinematic = P.has_back_stress();  // otherwise the back stress is zero and stays zero
  if (kinematic)
    for (int c = 0; c < 6; ++c) state.back_stress[c] = P.back_stress[c][p];
  else
    state.back_stress.setZero();
  // Abe, Johansson & Konagai 2005, sec. 7: dilatancy set to its flowing value once the particle flows.
  const bool flowing = state.equivalent_plastic_strain > body.granular.flowing_plastic_strain;
  const DruckerPrager& model = body.plastic[flowing ? 1 : 0];
  rotate_objectively(s, w_yz, w_xz, w_xy);
  if (kinematic) model.rotate_state(state, w_yz, w_xz, w_xy);
  const DruckerPragerResult r = model.update(s, state, de);  // Abe, Johansson & Konagai 2005, eq. 23-25, closed-form return
  P.plastic_strain[p] = state.equivalent_plastic_strain;
  if (kinematic)
    for (int c = 0; c < 6; ++c) P.back_stress[c][p] = state.back_stress[c];
  return r.plastic_work * P.volume[p];
}

// μ(I) (Jop et al. 2006 in the form of Dunatunga & Kamrin 2015): the rate enters through dt.
// P.plastic_strain accumulates the equivalent plastic shear strain (output only: the model has no
// state besides the stress).
[[gnu::always_inline]] inline double BodyMaterials::update_mu_i(const Body& body, ParticleStore& P, std::size_t p, Sym6& s,
                                                                const Sym6& de, double w_yz, double w_xz, double w_xy,
                                                                double dt) const {
  if (separated(body, P, p)) return release_separated(body, P, p, s);
  rotate_objectively(s, w_yz, w_xz, w_xy);
  const MuIResult r = body.mu_i[0].update(s, de, dt);
  P.plastic_strain[p] += r.plastic_shear_strain;
  return r.plastic_work * P.volume[p];
}

double BodyMaterials::update_particle(const Body& body, ParticleStore& P, std::size_t p, const StrainIncrements& inc,
                                      std::size_t k, double dt) const {
  Sym6 s, de;
  for (int c = 0; c < 6; ++c) {
    s[c] = P.stress[c][p];
    de[c] = inc.strain[c][k];
  }
  const double w_yz = inc.spin[0][k], w_xz = inc.spin[1][k], w_xy = inc.spin[2][k];
  double dissipated = 0.0;
  P.volume[p] *= 1.0 + trace(de);  // Edo & Matsubara 2015, eq. 35: rho_new = rho / (1 + tr d_eps)
  switch (body.model) {  // no default: -Wswitch names a model added without its update
    case MaterialModel::LinearElastic:
      rotate_objectively(s, w_yz, w_xz, w_xy);  // Jaumann rate, Hughes-Winget
      body.elastic.add_increment(s, de);        // Edo & Matsubara 2015, eq. 34
      break;
    case MaterialModel::DruckerPrager: dissipated = update_drucker_prager(body, P, p, s, de, w_yz, w_xz, w_xy); break;
    case MaterialModel::MuI: dissipated = update_mu_i(body, P, p, s, de, w_yz, w_xz, w_xy, dt); break;
  }
  for (int c = 0; c < 6; ++c) {
    P.stress[c][p] = s[c];
    P.strain[c][p] += de[c];
  }
  return dissipated;
}

void BodyMaterials::update_run(const Body& body, ParticleStore& P, std::size_t begin, std::size_t end,
                               std::size_t chunk_begin, const StrainIncrements& inc, double dt,
                               double& dissipated) const {
  // The vector kernels take linear elastic, μ(I) and Drucker-Prager bodies without a back stress; each
  // lane computes what update_particle would, bit for bit (solver/material_kernels.hpp).
  const bool lanes = vector_kernels_enabled() &&
                     (body.model == MaterialModel::LinearElastic || body.model == MaterialModel::MuI ||
                      (body.model == MaterialModel::DruckerPrager && !P.has_back_stress()));
  MuIKernelConstants mu_i_constants = body.mu_i_lanes;
  mu_i_constants.dt = dt;
  MaterialKernelFields fields;
  if (lanes) {
    for (int c = 0; c < 6; ++c) {
      fields.stress[c] = P.stress[c].data();
      fields.strain[c] = P.strain[c].data();
      fields.strain_increment[c] = inc.strain[c].data();
    }
    for (int c = 0; c < 3; ++c) fields.spin[c] = inc.spin[c].data();
    fields.volume = P.volume.data();
    fields.volume0 = P.volume0.data();
    fields.plastic_strain = P.plastic_strain.data();
    fields.chunk_begin = chunk_begin;
  }
  std::size_t p = begin;
  while (p < end) {
    KernelStop stop{p, end - p};
    if (lanes) {
      if (body.model == MaterialModel::LinearElastic)
        stop = update_elastic_lanes(fields, ElasticKernelConstants{body.elastic.lambda, body.elastic.shear}, p, end);
      else if (body.model == MaterialModel::DruckerPrager)
        stop = update_drucker_prager_lanes(fields, body.drucker_prager_lanes, p, end, dissipated);
      else
        stop = update_mu_i_lanes(fields, mu_i_constants, p, end, dissipated);
    }
    const std::size_t scalar_end = std::min(end, stop.next + stop.scalar_count);
    for (std::size_t q = stop.next; q < scalar_end; ++q)
      dissipated += update_particle(body, P, q, inc, q - chunk_begin, dt);
    p = scalar_end;
  }
}

bool BodyMaterials::shared_wave_rate_rule(WaveRateRule& rule) const {
  auto rule_of = [](const Body& b) {  // wave_speed_volume's cap, as one number (0: no cap)
    const double ratio = b.granular.separation_volume_ratio;
    const bool capped = (b.model == MaterialModel::DruckerPrager || b.model == MaterialModel::MuI) && ratio > 0.0;
    return WaveRateRule{b.p_wave_modulus, capped ? ratio : 0.0};
  };
  if (bodies_.empty()) return false;
  rule = rule_of(bodies_[0]);
  for (const Body& b : bodies_) {
    const WaveRateRule r = rule_of(b);
    if (r.modulus != rule.modulus || r.cap_ratio != rule.cap_ratio) return false;
  }
  return true;
}

double BodyMaterials::update(ParticleStore& P, std::size_t begin, std::size_t end, const StrainIncrements& inc,
                             double dt) const {
  double dissipated = 0.0;
  for (std::size_t p = begin; p < end;) {  // runs of particles of one body
    std::size_t run_end = p + 1;
    while (run_end < end && P.body[run_end] == P.body[p]) ++run_end;
    update_run(bodies_[P.body[p]], P, p, run_end, begin, inc, dt, dissipated);
    p = run_end;
  }
  return dissipated;
}

}  // namespace talus
