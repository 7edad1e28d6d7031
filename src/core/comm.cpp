#include "talus/core/comm.hpp"

#include "talus/core/error.hpp"

#include <algorithm>
#include <cstdlib>
#include <limits>

#ifdef TALUS_HAVE_MPI
// The C API only: in C++ mode Open MPI's header also pulls in its deprecated C++ bindings, whose
// symbols live in libmpi_cxx, which MPI::MPI_C does not link.
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

namespace talus {

namespace {
#ifdef TALUS_HAVE_MPI
bool mpi_running() {
  int initialised = 0, finalised = 0;
  MPI_Initialized(&initialised);
  MPI_Finalized(&finalised);
  return initialised && !finalised;
}
constexpr int kExchangeTag = 7301;
#endif
}  // namespace

bool mpi_built() {
#ifdef TALUS_HAVE_MPI
  return true;
#else
  return false;
#endif
}

Comm Comm::world() {
  Comm c;
#ifdef TALUS_HAVE_MPI
  if (mpi_running()) {
    MPI_Comm_rank(MPI_COMM_WORLD, &c.rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &c.size_);
  }
#endif
  return c;
}

void Comm::allgather_bytes(const void* value, std::size_t bytes, void* out) const {
  if (size_ == 1) {
    std::memcpy(out, value, bytes);
    return;
  }
#ifdef TALUS_HAVE_MPI
  MPI_Allgather(value, static_cast<int>(bytes), MPI_BYTE, out, static_cast<int>(bytes), MPI_BYTE, MPI_COMM_WORLD);
#endif
}

std::vector<double> Comm::sum_in_rank_order(const std::vector<double>& local) const {
  if (size_ == 1) return local;
  std::vector<double> all(local.size() * size_);
#ifdef TALUS_HAVE_MPI
  MPI_Allgather(local.data(), static_cast<int>(local.size()), MPI_DOUBLE, all.data(), static_cast<int>(local.size()),
                MPI_DOUBLE, MPI_COMM_WORLD);
#endif
  std::vector<double> total(local.size(), 0.0);
  for (int r = 0; r < size_; ++r)
    for (std::size_t i = 0; i < local.size(); ++i) total[i] += all[r * local.size() + i];
  return total;
}

std::vector<std::int64_t> Comm::sum_in_rank_order(const std::vector<std::int64_t>& local) const {
  if (size_ == 1) return local;
  std::vector<std::int64_t> all(local.size() * size_);
#ifdef TALUS_HAVE_MPI
  MPI_Allgather(local.data(), static_cast<int>(local.size()), MPI_INT64_T, all.data(), static_cast<int>(local.size()),
                MPI_INT64_T, MPI_COMM_WORLD);
#endif
  std::vector<std::int64_t> total(local.size(), 0);
  for (int r = 0; r < size_; ++r)
    for (std::size_t i = 0; i < local.size(); ++i) total[i] += all[r * local.size() + i];
  return total;
}

double Comm::min(double local) const {
  const std::vector<double> all = allgather(local);
  return *std::min_element(all.begin(), all.end());
}

bool Comm::any(bool local) const {
  const std::vector<unsigned char> all = allgather(static_cast<unsigned char>(local ? 1 : 0));
  return std::any_of(all.begin(), all.end(), [](unsigned char f) { return f != 0; });
}

void Comm::agree(const std::function<void()>& local) const {
  if (size_ == 1) {
    local();
    return;
  }
  std::string failure;
  Error::Kind kind = Error::Kind::Input;
  try {
    local();
  } catch (const Error& e) {
    failure = *e.what() ? e.what() : "failed";
    kind = e.kind();
  }
  if (!any(!failure.empty())) return;
  std::vector<std::int64_t> counts;
  const std::vector<char> all = gather(std::vector<char>(failure.begin(), failure.end()), &counts);
  std::string first;
  std::size_t at = 0;
  for (std::size_t r = 0; r < counts.size(); ++r) {  // (rank 0 alone has the counts)
    const auto n = static_cast<std::size_t>(counts[r]);
    if (first.empty() && n > 0)
      first = (r == 0 ? std::string() : "on rank " + std::to_string(r) + " of " + std::to_string(size_) + ": ") +
              std::string(all.data() + at, n);
    at += n;
  }
  throw Error(kind, root() ? first : failure.empty() ? std::string("another rank failed") : failure).mark_agreed();
}

std::vector<unsigned char> Comm::gather_bytes(const void* data, std::size_t bytes, std::vector<std::int64_t>& counts) const {
  counts.assign(1, static_cast<std::int64_t>(bytes));
  if (size_ == 1) {
    std::vector<unsigned char> out(bytes);
    if (bytes) std::memcpy(out.data(), data, bytes);
    return out;
  }
  std::vector<unsigned char> out;
#ifdef TALUS_HAVE_MPI
  const std::int64_t mine = static_cast<std::int64_t>(bytes);
  counts.assign(size_, 0);
  MPI_Gather(&mine, 1, MPI_INT64_T, counts.data(), 1, MPI_INT64_T, 0, MPI_COMM_WORLD);
  // Point-to-point rather than MPI_Gatherv, whose int counts limit a rank's share to 2 GB.
  constexpr std::int64_t kChunk = kMaxMessageBytes;
  if (rank_ == 0) {
    std::int64_t total = 0;
    for (std::int64_t c : counts) total += c;
    out.resize(static_cast<std::size_t>(total));
    if (bytes) std::memcpy(out.data(), data, bytes);
    std::int64_t at = counts[0];
    for (int r = 1; r < size_; ++r) {
      for (std::int64_t done = 0; done < counts[r]; done += kChunk) {
        const int n = static_cast<int>(std::min(kChunk, counts[r] - done));
        MPI_Recv(out.data() + at + done, n, MPI_BYTE, r, kExchangeTag + 1, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
      }
      at += counts[r];
    }
  } else {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::int64_t done = 0; done < mine; done += kChunk) {
      const int n = static_cast<int>(std::min(kChunk, mine - done));
      MPI_Send(p + done, n, MPI_BYTE, 0, kExchangeTag + 1, MPI_COMM_WORLD);
    }
    counts.clear();
  }
#endif
  return out;
}

std::vector<std::vector<unsigned char>> Comm::exchange(const std::vector<int>& send_to,
                                                       const std::vector<std::vector<unsigned char>>& to_peer,
                                                       const std::vector<int>& receive_from,
                                                       std::int64_t piece_bytes) const {
  std::vector<std::vector<unsigned char>> received(receive_from.size());
#ifdef TALUS_HAVE_MPI
  if (send_to.empty() && receive_from.empty()) return received;
  // MPI counts are ints: a buffer goes in pieces of piece_bytes, the last one shorter (empty when the
  // size is a multiple), so a receiver reads until a short piece. Messages between two ranks on one
  // tag arrive in the order they were sent. (One message of a migration of more than about 10 M
  // particles to one neighbour passed 2 GB, and its count wrapped.)
  const std::int64_t piece = std::clamp<std::int64_t>(piece_bytes, 1, kMaxMessageBytes);
  std::vector<MPI_Request> sends;
  for (std::size_t i = 0; i < send_to.size(); ++i) {
    const auto size = static_cast<std::int64_t>(to_peer[i].size());
    for (std::int64_t done = 0;; done += piece) {
      const std::int64_t n = std::min(piece, size - done);
      sends.emplace_back();
      MPI_Isend(to_peer[i].data() + done, static_cast<int>(n), MPI_BYTE, send_to[i], kExchangeTag, MPI_COMM_WORLD,
                &sends.back());
      if (n < piece) break;
    }
  }
  for (std::size_t i = 0; i < receive_from.size(); ++i) {
    for (;;) {
      MPI_Status status;
      MPI_Probe(receive_from[i], kExchangeTag, MPI_COMM_WORLD, &status);
      int count = 0;
      MPI_Get_count(&status, MPI_BYTE, &count);
      const std::size_t at = received[i].size();
      received[i].resize(at + static_cast<std::size_t>(count));
      MPI_Recv(received[i].data() + at, count, MPI_BYTE, receive_from[i], kExchangeTag, MPI_COMM_WORLD,
               MPI_STATUS_IGNORE);
      if (count < piece) break;
    }
  }
  MPI_Waitall(static_cast<int>(sends.size()), sends.data(), MPI_STATUSES_IGNORE);
#else
  (void)send_to;
  (void)to_peer;
  (void)piece_bytes;
#endif
  return received;
}

std::vector<std::int64_t> Comm::alltoall(const std::vector<std::int64_t>& per_rank) const {
  if (size_ == 1) return per_rank;
  std::vector<std::int64_t> out(static_cast<std::size_t>(size_));
#ifdef TALUS_HAVE_MPI
  MPI_Alltoall(per_rank.data(), 1, MPI_INT64_T, out.data(), 1, MPI_INT64_T, MPI_COMM_WORLD);
#endif
  return out;
}

std::string Comm::broadcast(const std::string& from_root) const {
  if (size_ == 1) return from_root;
  std::string s = from_root;
#ifdef TALUS_HAVE_MPI
  std::int64_t n = static_cast<std::int64_t>(s.size());
  MPI_Bcast(&n, 1, MPI_INT64_T, 0, MPI_COMM_WORLD);
  s.resize(static_cast<std::size_t>(n));
  MPI_Bcast(s.data(), static_cast<int>(n), MPI_CHAR, 0, MPI_COMM_WORLD);
#endif
  return s;
}

void Comm::barrier() const {
#ifdef TALUS_HAVE_MPI
  if (size_ > 1) MPI_Barrier(MPI_COMM_WORLD);
#endif
}

void Comm::abort(int code) const {
#ifdef TALUS_HAVE_MPI
  if (mpi_running()) MPI_Abort(MPI_COMM_WORLD, code);
#endif
  std::exit(code);
}

bool MpiSession::launched_by_mpirun() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_SIZE"})
    if (std::getenv(name)) return true;
  return false;
}

MpiSession::MpiSession(int& argc, char**& argv) {
#ifdef TALUS_HAVE_MPI
  if (!launched_by_mpirun()) return;
  int provided = 0;
  // OpenMP threads inside each rank; only the main thread calls MPI.
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  active_ = true;
#else
  (void)argc;
  (void)argv;
#endif
}

MpiSession::~MpiSession() {
#ifdef TALUS_HAVE_MPI
  if (active_ && mpi_running()) MPI_Finalize();
#endif
}

}  // namespace talus
