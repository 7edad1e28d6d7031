#pragma once
// Comm: the ranks of a distributed run (MPI), or the one rank of a serial run.
//
// talus is one binary for both. Built with MPI (TALUS_MPI) and started by mpirun, MpiSession
// initialises MPI and Comm::world() spans its ranks; started without mpirun (or built without MPI)
// there is one rank, MPI is never initialised, and every call below is a copy or a no-op, so a
// serial run behaves exactly as a build without MPI.
//
// Only comm.cpp includes <mpi.h>: the templates below move trivially copyable values as bytes.
// Every collective returns per-rank values in rank order, and callers combine them in that order,
// so a reduction has the same bits from run to run and for any thread count (docs/architecture.md,
// "Distributed runs").
#include <cstddef>
#include <cstdint>
#include <limits>
#include <cstring>
#include <functional>
#include <string>
#include <type_traits>
#include <vector>

namespace talus {

class Comm {
 public:
  /// One rank (a serial run).
  Comm() = default;
  /// All ranks of the job when MPI is running (MpiSession), else one rank.
  static Comm world();

  int rank() const { return rank_; }
  int size() const { return size_; }
  bool distributed() const { return size_ > 1; }
  bool root() const { return rank_ == 0; }

  /// Each rank's `value`, in rank order, on every rank.
  template <class T>
  std::vector<T> allgather(const T& value) const {
    static_assert(std::is_trivially_copyable_v<T>);
    std::vector<T> out(static_cast<std::size_t>(size_));
    allgather_bytes(&value, sizeof(T), out.data());
    return out;
  }
  /// Element-wise sum of equal-length vectors over the ranks, added in rank order.
  std::vector<double> sum_in_rank_order(const std::vector<double>& local) const;
  std::vector<std::int64_t> sum_in_rank_order(const std::vector<std::int64_t>& local) const;
  double sum_in_rank_order(double local) const { return sum_in_rank_order(std::vector<double>{local})[0]; }
  double min(double local) const;
  bool any(bool local) const;

  /// Runs `local`, work that may fail on one rank alone (its slab, its machine, its copy of a file),
  /// and agrees on the outcome: when it threw an Error on any rank, every rank throws one, and rank
  /// 0's carries the first failure's message, naming the rank when it was not rank 0 (each marked
  /// Error::agreed: rank 0 alone need say it, and no rank waits for another). Without this
  /// the ranks that went on waited in their next collective for the one that had stopped, forever.
  /// Collective; with one rank it only runs `local`.
  void agree(const std::function<void()>& local) const;

  /// The ranks' vectors concatenated in rank order on rank 0 (empty elsewhere); `counts` (if given)
  /// receives each rank's length on rank 0.
  /// The result has the input's allocator (a ParticleArray gathers into a ParticleArray).
  template <class T, class Allocator>
  std::vector<T, Allocator> gather(const std::vector<T, Allocator>& local,
                                   std::vector<std::int64_t>* counts = nullptr) const {
    static_assert(std::is_trivially_copyable_v<T>);
    std::vector<std::int64_t> byte_counts;
    std::vector<unsigned char> bytes = gather_bytes(local.data(), local.size() * sizeof(T), byte_counts);
    std::vector<T, Allocator> out(bytes.size() / sizeof(T));
    if (!bytes.empty()) std::memcpy(out.data(), bytes.data(), bytes.size());
    if (counts) {
      counts->clear();
      for (std::int64_t b : byte_counts) counts->push_back(b / static_cast<std::int64_t>(sizeof(T)));
    }
    return out;
  }

  /// Point-to-point exchange: send to_peer[i] to peers[i] and return what peers[i] sent here. Every
  /// peer must call it with this rank in its list (the lists are symmetric).
  std::vector<std::vector<unsigned char>> exchange(const std::vector<int>& peers,
                                                   const std::vector<std::vector<unsigned char>>& to_peer) const {
    return exchange(peers, to_peer, peers);
  }
  /// The same with lists that need not be symmetric: send to_peer[i] to send_to[i], and return what
  /// each rank of receive_from sent (in that order). Each rank's send_to must list exactly the ranks
  /// whose receive_from lists it. A buffer of any size goes in messages of at most `piece_bytes`
  /// (MPI counts are ints; tests pass small pieces, every rank the same).
  std::vector<std::vector<unsigned char>> exchange(const std::vector<int>& send_to,
                                                   const std::vector<std::vector<unsigned char>>& to_peer,
                                                   const std::vector<int>& receive_from,
                                                   std::int64_t piece_bytes = kMaxMessageBytes) const;
  /// The largest message the point-to-point calls send: half of MPI's int count.
  static constexpr std::int64_t kMaxMessageBytes = std::numeric_limits<int>::max() / 2;
  /// All-to-all of one count per rank: out[r] is what rank r put at this rank's index.
  std::vector<std::int64_t> alltoall(const std::vector<std::int64_t>& per_rank) const;

  /// Rank 0's string on every rank.
  std::string broadcast(const std::string& from_root) const;
  void barrier() const;
  /// End the whole job with `code` (MPI_Abort): a rank that cannot go on must not leave the others
  /// waiting in a collective. A serial run exits.
  [[noreturn]] void abort(int code) const;

 private:
  void allgather_bytes(const void* value, std::size_t bytes, void* out) const;
  std::vector<unsigned char> gather_bytes(const void* data, std::size_t bytes, std::vector<std::int64_t>& counts) const;
  int rank_ = 0;
  int size_ = 1;
};

/// Whether this binary was built with MPI (TALUS_MPI).
bool mpi_built();

/// MPI for the life of the program: initialised when the process was started by mpirun (its
/// environment says so) and the build has MPI; finalised at the end. Without mpirun nothing happens.
class MpiSession {
 public:
  MpiSession(int& argc, char**& argv);
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;
  /// Whether MPI was initialised by this session.
  bool active() const { return active_; }
  /// Whether the environment says mpirun started this process (OMPI_COMM_WORLD_SIZE, PMIX_RANK, PMI_SIZE).
  static bool launched_by_mpirun();

 private:
  bool active_ = false;
};

/// Byte buffers for the exchanges: append and read trivially copyable values.
template <class T>
void append_bytes(std::vector<unsigned char>& buffer, const T* values, std::size_t count) {
  static_assert(std::is_trivially_copyable_v<T>);
  const std::size_t at = buffer.size();
  buffer.resize(at + count * sizeof(T));
  if (count) std::memcpy(buffer.data() + at, values, count * sizeof(T));
}
template <class T>
void append_bytes(std::vector<unsigned char>& buffer, const T& value) {
  append_bytes(buffer, &value, 1);
}
/// Reads values from a buffer in the order they were appended.
class ByteReader {
 public:
  explicit ByteReader(const std::vector<unsigned char>& buffer) : buffer_(buffer) {}
  template <class T>
  void read(T* values, std::size_t count) {
    static_assert(std::is_trivially_copyable_v<T>);
    if (count) std::memcpy(values, buffer_.data() + at_, count * sizeof(T));
    at_ += count * sizeof(T);
  }
  template <class T>
  T read() {
    T value;
    read(&value, 1);
    return value;
  }
  bool done() const { return at_ >= buffer_.size(); }

 private:
  const std::vector<unsigned char>& buffer_;
  std::size_t at_ = 0;
};

}  // namespace talus
