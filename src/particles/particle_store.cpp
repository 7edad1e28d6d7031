#include "talus/particles/particle_store.hpp"

#include <omp.h>

#include <cmath>

namespace talus {

std::size_t ParticleStore::add(std::int64_t particle_id, const Vec3& position, const Vec3& velocity,
                               double particle_mass, double particle_volume,
                               std::uint16_t body_index) {
  id.push_back(particle_id);
  for (int d = 0; d < 3; ++d) {
    x[d].push_back(position[d]);
    v[d].push_back(velocity[d]);
  }
  mass.push_back(particle_mass);
  volume.push_back(particle_volume);
  volume0.push_back(particle_volume);
  for (int c = 0; c < 6; ++c) {
    stress[c].push_back(0.0);
    strain[c].push_back(0.0);
  }
  body.push_back(body_index);
  if (plastic_enabled_) plastic_strain.push_back(0.0);
  if (back_stress_enabled_)
    for (auto& b : back_stress) b.push_back(0.0);
  if (domain_enabled_)
    for (auto& l : domain) l.push_back(0.5 * std::cbrt(particle_volume));
  return id.size() - 1;
}

void ParticleStore::reserve(std::size_t n) {
  id.reserve(n);
  for (int d = 0; d < 3; ++d) {
    x[d].reserve(n);
    v[d].reserve(n);
  }
  mass.reserve(n);
  volume.reserve(n);
  volume0.reserve(n);
  for (int c = 0; c < 6; ++c) {
    stress[c].reserve(n);
    strain[c].reserve(n);
  }
  body.reserve(n);
}

void ParticleStore::enable_plastic_state(bool with_back_stress) {
  plastic_enabled_ = true;
  plastic_strain.assign(size(), 0.0);
  if (!with_back_stress) return;
  back_stress_enabled_ = true;
  for (auto& b : back_stress) b.assign(size(), 0.0);
}

void ParticleStore::enable_domain_state() {
  domain_enabled_ = true;
  for (auto& l : domain) {
    l.resize(size());
    for (std::size_t p = 0; p < size(); ++p) l[p] = 0.5 * std::cbrt(volume0[p]);  // l_p0 (Edo & Matsubara 2015, sec. 3)
  }
}

namespace {

template <class T>
void permute_field(std::vector<T>& field, const std::vector<std::uint32_t>& order,
                   std::vector<T>& scratch) {
  if (field.empty()) return;
  const std::size_t n = order.size();
  scratch.resize(n);
  const T* src = field.data();
  T* dst = scratch.data();
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < n; ++i) dst[i] = src[order[i]];
  field.swap(scratch);
}

}  // namespace

void ParticleStore::permute(const std::vector<std::uint32_t>& order) {
  permute_field(id, order, id_scratch_);
  permute_field(body, order, body_scratch_);
  for_each_double_array([&](const char*, std::vector<double>& f) { permute_field(f, order, scratch_); });
}

std::size_t ParticleStore::bytes() const {
  std::size_t b = id.capacity() * sizeof(std::int64_t) + body.capacity() * sizeof(std::uint16_t);
  for_each_double_array([&](const char*, const std::vector<double>& f) { b += f.capacity() * sizeof(double); });
  return b;
}

}  // namespace talus
