// Message costs between MPI ranks, for the weak-scaling model of docs/performance.md ("Distributed
// runs (MPI)"). Not part of the talus build: compile and run it by hand (tools/mpi_message_costs.sh):
//
//   mpicxx -O2 -std=c++20 tools/mpi_message_costs.cpp -o /tmp/mpi_message_costs
//   mpirun -np 2 /tmp/mpi_message_costs > costs.json
//
// Three measurements, each the median of `repeats` timed rounds after warm-up rounds:
//   pingpong:  rank 0 sends n bytes, rank 1 sends them back; half the round trip (latency + n / bandwidth);
//   exchange:  every rank sends n bytes to its neighbours and receives theirs at once, the pattern of
//              talus's node-sum exchange (Comm::exchange: MPI_Isend, MPI_Probe, MPI_Recv, MPI_Waitall);
//   allgather: MPI_Allgather of a 24-byte record, the size of the solver's one collective a step;
//   tiles:     the whole node-sum exchange as TileExchange::sum_shared does it for `t` shared tiles of
//              4x4x4 nodes and f fields (7 after P2G, 3 after the MUSL remap): pack each tile's fields
//              from grid arrays 4x larger than the shared band, exchange, add mine and theirs in rank
//              order, write back. Each rank's largest time of the round. "tiles": the buffers
//              allocated anew in every call, as TileExchange and Comm::exchange do; "tiles_reused":
//              kept across calls (on this VM a freshly faulted page costs up to ~30 us).
#include <mpi.h>

#include <algorithm>
#include <cstdio>
#include <vector>

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

int rank_ = 0, size_ = 1;

/// Half the round trip of n bytes between ranks 0 and 1 (others idle).
double pingpong(std::vector<char>& buffer, int n, int repeats) {
  std::vector<double> t;
  for (int r = -3; r < repeats; ++r) {
    MPI_Barrier(MPI_COMM_WORLD);
    const double start = MPI_Wtime();
    if (rank_ == 0) {
      MPI_Send(buffer.data(), n, MPI_BYTE, 1, 1, MPI_COMM_WORLD);
      MPI_Recv(buffer.data(), n, MPI_BYTE, 1, 2, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    } else if (rank_ == 1) {
      MPI_Recv(buffer.data(), n, MPI_BYTE, 0, 1, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
      MPI_Send(buffer.data(), n, MPI_BYTE, 0, 2, MPI_COMM_WORLD);
    }
    if (r >= 0) t.push_back(0.5 * (MPI_Wtime() - start));
  }
  return median(t);
}

/// One exchange of n bytes with each slab neighbour (rank +- 1), as Comm::exchange does it.
double exchange(std::vector<char>& out, std::vector<char>& in, int n, int repeats) {
  std::vector<int> peers;
  if (rank_ > 0) peers.push_back(rank_ - 1);
  if (rank_ + 1 < size_) peers.push_back(rank_ + 1);
  std::vector<double> t;
  for (int r = -3; r < repeats; ++r) {
    MPI_Barrier(MPI_COMM_WORLD);
    const double start = MPI_Wtime();
    std::vector<MPI_Request> sends(peers.size());
    for (std::size_t i = 0; i < peers.size(); ++i)
      MPI_Isend(out.data() + i * n, n, MPI_BYTE, peers[i], 3, MPI_COMM_WORLD, &sends[i]);
    for (std::size_t i = 0; i < peers.size(); ++i) {
      MPI_Status status;
      MPI_Probe(peers[i], 3, MPI_COMM_WORLD, &status);
      MPI_Recv(in.data() + i * n, n, MPI_BYTE, peers[i], 3, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    }
    MPI_Waitall(static_cast<int>(sends.size()), sends.data(), MPI_STATUSES_IGNORE);
    double mine = MPI_Wtime() - start, slowest = 0.0;
    MPI_Allreduce(&mine, &slowest, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    if (r >= 0) t.push_back(slowest);
  }
  return median(t);
}

/// The node-sum exchange of `tiles` shared tiles and `fields` fields with each neighbour.
double tile_exchange(int tiles, int fields, int repeats, bool reuse) {
  constexpr int kTileNodes = 64;
  const std::size_t grid_tiles = 4 * static_cast<std::size_t>(tiles);
  std::vector<std::vector<double>> grid(fields, std::vector<double>(grid_tiles * kTileNodes, 1.0));
  std::vector<int> peers;
  if (rank_ > 0) peers.push_back(rank_ - 1);
  if (rank_ + 1 < size_) peers.push_back(rank_ + 1);
  const std::size_t message = static_cast<std::size_t>(tiles) * fields * kTileNodes;
  std::vector<double> t;
  std::vector<std::vector<double>> kept_out(peers.size()), kept_in(peers.size());
  for (int r = -3; r < repeats; ++r) {
    MPI_Barrier(MPI_COMM_WORLD);
    const double start = MPI_Wtime();
    std::vector<std::vector<double>> fresh_out(peers.size()), fresh_in(peers.size());
    auto& out = reuse ? kept_out : fresh_out;
    auto& in = reuse ? kept_in : fresh_in;
    std::vector<MPI_Request> sends(peers.size());
    for (std::size_t i = 0; i < peers.size(); ++i) {
      out[i].clear();
      out[i].reserve(message);
      for (int k = 0; k < tiles; ++k)  // every 4th tile of the grid is shared: strided, as in a real band
        for (int f = 0; f < fields; ++f)
          out[i].insert(out[i].end(), grid[f].begin() + (4 * k) * kTileNodes, grid[f].begin() + (4 * k + 1) * kTileNodes);
      MPI_Isend(out[i].data(), static_cast<int>(message * sizeof(double)), MPI_BYTE, peers[i], 4, MPI_COMM_WORLD, &sends[i]);
    }
    for (std::size_t i = 0; i < peers.size(); ++i) {
      MPI_Status status;
      MPI_Probe(peers[i], 4, MPI_COMM_WORLD, &status);
      in[i].resize(message);
      MPI_Recv(in[i].data(), static_cast<int>(message * sizeof(double)), MPI_BYTE, peers[i], 4, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    }
    for (std::size_t i = 0; i < peers.size(); ++i)
      for (int k = 0; k < tiles; ++k)
        for (int f = 0; f < fields; ++f) {
          double* mine = grid[f].data() + (4 * k) * kTileNodes;
          const double* theirs = in[i].data() + (static_cast<std::size_t>(k) * fields + f) * kTileNodes;
          double sum[kTileNodes];
          for (int s = 0; s < kTileNodes; ++s) sum[s] = peers[i] > rank_ ? mine[s] + theirs[s] : theirs[s] + mine[s];
          std::copy(sum, sum + kTileNodes, mine);
        }
    MPI_Waitall(static_cast<int>(sends.size()), sends.data(), MPI_STATUSES_IGNORE);
    double me = MPI_Wtime() - start, slowest = 0.0;
    MPI_Allreduce(&me, &slowest, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    if (r >= 0) t.push_back(slowest);
  }
  return median(t);
}

double allgather(int repeats) {
  struct Record {
    double dt;
    long long particles;
    unsigned char sort, tiles;
  } mine{1e-4, 1000, 0, 0};
  static_assert(sizeof(Record) == 24);
  std::vector<Record> all(size_);
  std::vector<double> t;
  for (int r = -10; r < repeats; ++r) {
    MPI_Barrier(MPI_COMM_WORLD);
    const double start = MPI_Wtime();
    MPI_Allgather(&mine, sizeof(Record), MPI_BYTE, all.data(), sizeof(Record), MPI_BYTE, MPI_COMM_WORLD);
    double me = MPI_Wtime() - start, slowest = 0.0;
    MPI_Allreduce(&me, &slowest, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    if (r >= 0) t.push_back(slowest);
  }
  return median(t);
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
  if (size_ < 2) {
    if (rank_ == 0) std::fprintf(stderr, "mpi_message_costs: run it with mpirun -np 2 (or more)\n");
    MPI_Finalize();
    return 2;
  }
  const int max_bytes = 1 << 26;  // 64 MiB
  std::vector<char> a(2 * static_cast<std::size_t>(max_bytes), 1), b(2 * static_cast<std::size_t>(max_bytes), 0);
  if (rank_ == 0) std::printf("{\n  \"ranks\": %d,\n  \"pingpong\": [", size_);
  bool first = true;
  for (int n = 8; n <= max_bytes; n *= 4) {
    const int repeats = n <= (1 << 16) ? 2000 : n <= (1 << 22) ? 100 : 20;
    const double t = pingpong(a, n, repeats);
    if (rank_ == 0) std::printf("%s\n    {\"bytes\": %d, \"seconds\": %.4e}", first ? "" : ",", n, t);
    first = false;
  }
  if (rank_ == 0) std::printf("\n  ],\n  \"exchange\": [");
  first = true;
  for (int n = 8; n <= max_bytes; n *= 4) {
    const int repeats = n <= (1 << 16) ? 2000 : n <= (1 << 22) ? 100 : 20;
    const double t = exchange(a, b, n, repeats);
    if (rank_ == 0) std::printf("%s\n    {\"bytes\": %d, \"seconds\": %.4e}", first ? "" : ",", n, t);
    first = false;
  }
  for (const bool reuse : {false, true}) {
    if (rank_ == 0) std::printf("\n  ],\n  \"%s\": [", reuse ? "tiles_reused" : "tiles");
    first = true;
    for (int tiles : {50, 420, 1000})
      for (int fields : {7, 3}) {
        const double t = tile_exchange(tiles, fields, tiles <= 420 ? 50 : 20, reuse);
        if (rank_ == 0)
          std::printf("%s\n    {\"tiles\": %d, \"fields\": %d, \"bytes\": %d, \"seconds\": %.4e}", first ? "" : ",", tiles,
                      fields, tiles * fields * 64 * 8, t);
        first = false;
      }
  }
  const double g = allgather(5000);
  if (rank_ == 0) std::printf("\n  ],\n  \"allgather_24_bytes_seconds\": %.4e\n}\n", g);
  MPI_Finalize();
  return 0;
}
