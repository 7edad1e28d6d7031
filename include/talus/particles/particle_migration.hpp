#pragma once
// Moving particles between the ranks of a distributed run (SlabDecomposition says who owns what).
#include "talus/core/comm.hpp"
#include "talus/particles/particle_store.hpp"

#include <cstdint>
#include <string_view>
#include <vector>

namespace talus {

/// Collective: every particle p whose owner[p] is another rank goes there, with every allocated
/// array. The particles this rank keeps stay in their order, first; those received follow in the
/// order of their source ranks, each in its sender's order, so the result is the same from run to
/// run. Returns the number of particles this rank sent.
std::size_t migrate_particles(const Comm& comm, ParticleStore& particles, const std::vector<int>& owner);

/// Collective: every rank's particles concatenated in rank order, on rank 0; the other ranks get a
/// store with no particles. Both have the same allocated field groups as `local`. (For the outputs
/// that need all particles in one place: runout, deposit, checkpoint.)
ParticleStore gather_particles(const Comm& comm, const ParticleStore& local);

/// Every particle in one place for an output, without a copy where there is one place already:
/// in a run that is not distributed `get()` is the local store itself; in a distributed run it is
/// gather_particles' result (collective: every rank must construct one). The runout history took
/// a whole copy of the particles at every row before (a serial part of the run loop).
class AllParticles {
 public:
  AllParticles(const Comm& comm, const ParticleStore& local)
      : local_(local), gathered_(comm.distributed() ? gather_particles(comm, local) : ParticleStore()),
        distributed_(comm.distributed()) {}
  const ParticleStore& get() const { return distributed_ ? gathered_ : local_; }

 private:
  const ParticleStore& local_;
  ParticleStore gathered_;
  bool distributed_;
};

/// Whether the particle array of this name (ParticleStore's visitors) is in use in `store`: the
/// optional groups by the store's flags, which every rank sets alike.
bool particle_array_in_use(const ParticleStore& store, std::string_view name);

}  // namespace talus
