#include "talus/particles/particle_migration.hpp"

#include <string_view>

namespace talus {

// A rank holding no particle cannot tell from the arrays' sizes which groups are in use.
bool particle_array_in_use(const ParticleStore& P, const std::string_view name) {
  if (name.starts_with("plastic_strain")) return P.has_plastic_state();
  if (name.starts_with("back_stress")) return P.has_back_stress();
  if (name.starts_with("domain")) return P.has_domain_state();
  return true;
}

std::size_t migrate_particles(const Comm& comm, ParticleStore& P, const std::vector<int>& owner) {
  if (!comm.distributed()) return 0;
  const std::size_t n = P.size();
  const int me = comm.rank();
  // The particles for each rank, and those kept, in store order.
  std::vector<std::vector<std::uint32_t>> leaving(comm.size());
  std::vector<std::uint32_t> kept;
  kept.reserve(n);
  for (std::size_t p = 0; p < n; ++p) {
    if (owner[p] == me) kept.push_back(static_cast<std::uint32_t>(p));
    else leaving[owner[p]].push_back(static_cast<std::uint32_t>(p));
  }
  // Only the ranks that send or receive talk: an all-to-all of the counts first (MPI_Alltoall).
  std::vector<std::int64_t> counts_out(comm.size(), 0);
  for (int r = 0; r < comm.size(); ++r) counts_out[r] = r == me ? 0 : static_cast<std::int64_t>(leaving[r].size());
  const std::vector<std::int64_t> counts_in = comm.alltoall(counts_out);
  std::vector<int> send_to, receive_from;
  std::vector<std::vector<unsigned char>> out;
  std::size_t sent = 0;
  for (int r = 0; r < comm.size(); ++r) {
    if (counts_in[r] > 0) receive_from.push_back(r);
    if (counts_out[r] == 0) continue;
    send_to.push_back(r);
    std::vector<unsigned char> bytes;
    const auto& list = leaving[r];
    sent += list.size();
    append_bytes(bytes, static_cast<std::uint64_t>(list.size()));
    auto pack = [&](const char* name, const auto& array) {
      if (!particle_array_in_use(P, name)) return;
      for (std::uint32_t p : list) append_bytes(bytes, array[p]);
    };
    P.for_each_double_array(pack);
    P.for_each_integer_array(pack);
    out.push_back(std::move(bytes));
  }
  const auto in = comm.exchange(send_to, out, receive_from);  // received in source-rank order
  P.permute(kept);
  const std::size_t n_kept = P.size();
  // The arrays in use (sized n_kept after the permutation) grow by every received particle.
  std::size_t arriving = 0;
  std::vector<std::size_t> counts(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    ByteReader reader(in[i]);
    counts[i] = static_cast<std::size_t>(reader.read<std::uint64_t>());
    arriving += counts[i];
  }
  if (arriving == 0) return sent;
  std::vector<ByteReader> readers;
  for (const auto& bytes : in) {
    readers.emplace_back(bytes);
    readers.back().read<std::uint64_t>();
  }
  auto unpack = [&](const char* name, auto& array) {
    if (!particle_array_in_use(P, name)) return;
    array.resize(n_kept + arriving);
    std::size_t at = n_kept;
    for (std::size_t i = 0; i < in.size(); ++i) {
      readers[i].read(array.data() + at, counts[i]);
      at += counts[i];
    }
  };
  P.for_each_double_array(unpack);
  P.for_each_integer_array(unpack);
  return sent;
}

ParticleStore gather_particles(const Comm& comm, const ParticleStore& local) {
  ParticleStore all = local;
  if (!comm.distributed()) return all;
  auto gather = [&](const char* name, auto& array) {
    if (!particle_array_in_use(local, name)) return;
    array = comm.gather(array);
  };
  all.for_each_double_array(gather);
  all.for_each_integer_array(gather);
  return all;
}

}  // namespace talus
