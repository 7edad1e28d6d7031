#include "talus/particles/particle_store.hpp"

#include <omp.h>

#include <algorithm>
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

// new[i] = old[order[i]] through `buffer` (order.size() elements): gathered in one parallel loop,
// copied back in another, and the field shortened to the order's length.
template <class T>
void permute_field(ParticleArray<T>& field, std::span<const std::uint32_t> order, std::span<T> buffer) {
  if (field.empty()) return;
  const std::size_t n = order.size();
  const T* const src = field.data();
  T* const tmp = buffer.data();
  const std::uint32_t* const at = order.data();
#pragma omp parallel
  {
#pragma omp for schedule(static)
    for (std::size_t i = 0; i < n; ++i) tmp[i] = src[at[i]];
    // (the implicit barrier: every gather has read the old field)
    T* const dst = field.data();
#pragma omp for schedule(static)
    for (std::size_t i = 0; i < n; ++i) dst[i] = tmp[i];
  }
  field.resize(n);
}

}  // namespace

void ParticleStore::permute(std::span<const std::uint32_t> order, ParticleScratch& scratch, int plane) {
  const std::size_t n = order.size();  // (plane() throws when the scratch holds fewer)
  permute_field(id, order, scratch.plane<std::int64_t>(plane, n));
  permute_field(body, order, scratch.plane<std::uint16_t>(plane, n));
  for_each_double_array([&](const char*, ParticleArray<double>& f) { permute_field(f, order, scratch.plane<double>(plane, n)); });
}

void ParticleStore::permute(std::span<const std::uint32_t> order) {
  ParticleScratch scratch;
  scratch.reserve(order.size());
  permute(order, scratch, 0);
}

namespace {

template <class T>
void resize_for_copy(ParticleArray<T>& to, const ParticleArray<T>& from) {
  if (to.size() != from.size()) to.resize(from.size());
}

// Copies from[begin, end) into to (sized already).
template <class T>
void copy_slice(ParticleArray<T>& to, const ParticleArray<T>& from, std::size_t begin, std::size_t end) {
  const std::size_t e = std::min(end, from.size());
  if (begin < e) std::copy(from.begin() + begin, from.begin() + e, to.begin() + begin);
}

}  // namespace

void ParticleStore::copy_from(const ParticleStore& other) {
  plastic_enabled_ = other.plastic_enabled_;
  back_stress_enabled_ = other.back_stress_enabled_;
  domain_enabled_ = other.domain_enabled_;
  resize_for_copy(id, other.id);
  resize_for_copy(body, other.body);
  // (the double arrays of both stores are visited in the same order)
  std::vector<ParticleArray<double>*> to;
  std::vector<const ParticleArray<double>*> from;
  for_each_double_array([&](const char*, ParticleArray<double>& a) { to.push_back(&a); });
  other.for_each_double_array([&](const char*, const ParticleArray<double>& a) { from.push_back(&a); });
  for (std::size_t a = 0; a < to.size(); ++a) resize_for_copy(*to[a], *from[a]);
  const std::size_t n = other.size();
#pragma omp parallel
  {
    const std::size_t threads = static_cast<std::size_t>(omp_get_num_threads());
    const std::size_t t = static_cast<std::size_t>(omp_get_thread_num());
    const std::size_t begin = n * t / threads, end = n * (t + 1) / threads;
    copy_slice(id, other.id, begin, end);
    copy_slice(body, other.body, begin, end);
    for (std::size_t a = 0; a < to.size(); ++a) copy_slice(*to[a], *from[a], begin, end);
  }
}

std::size_t ParticleStore::bytes() const {
  std::size_t b = id.capacity() * sizeof(std::int64_t) + body.capacity() * sizeof(std::uint16_t);
  for_each_double_array([&](const char*, const ParticleArray<double>& f) { b += f.capacity() * sizeof(double); });
  return b;
}

}  // namespace talus
