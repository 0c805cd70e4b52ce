// The ranks of a distributed run: which process this is among those an MPI launcher (mpirun) started, and
// the few collectives training and rendering need. Without MPI (not built in, or not launched by mpirun) the
// world is one rank and every collective is the identity, so library code calls them unconditionally.
//
// Data-parallel training: every rank draws the same batch, trains a contiguous share of its ray indices, and the
// flat gradient buffers are summed across ranks before the identical Adam step (docs/ARCHITECTURE.md, "Ranks").
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/error.hpp"

namespace mipnerf::parallel {

// An error every rank raises at the same point (a collective check that failed): each rank stops cleanly, and
// only rank 0 prints it, so the user reads it once.
class CollectiveError : public Error {
 public:
  using Error::Error;
};

class World {
 public:
  int rank() const { return rank_; }
  int size() const { return size_; }
  int local_rank() const { return local_rank_; }  // among the ranks on this host
  int local_size() const { return local_size_; }
  bool is_root() const { return rank_ == 0; }
  bool distributed() const { return size_ > 1; }

  // Element-wise sums over the ranks, in place; every rank receives the same bits (MPI_Allreduce).
  void sum_in_place(float* values, size_t count) const;
  void sum_in_place(double* values, size_t count) const;
  // Every rank's value, in rank order.
  std::vector<uint64_t> all_gather(uint64_t value) const;
  // Rank 0's text on every rank.
  void broadcast(std::string& text) const;
  // Rank r holds the elements [offsets[r], offsets[r + 1]) of `data` (size offsets.back()); afterwards every rank
  // holds them all (MPI_Allgatherv). offsets has size() + 1 entries.
  void all_gather_segments(float* data, const std::vector<size_t>& offsets) const;
  void barrier() const;

 private:
  friend class Session;
  int rank_ = 0, size_ = 1, local_rank_ = 0, local_size_ = 1;
};

// The process's world: one rank until a Session started MPI.
const World& world();

// How many processes a launcher says it started (Open MPI, MPICH/PMI, PMIx environments), 1 when none.
int launcher_world_size();

// This process's rank as the launcher's environment gives it (0 when none): in a build without MPI, the copies
// mpirun started know from it which one speaks.
int launcher_rank();

// Starts MPI when a launcher started this process (and finalizes it on destruction); without MPI built in, a
// launch of more than one process is refused with what to do. Construct once, first thing in main.
class Session {
 public:
  Session(int* argc, char*** argv);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  // Stops every rank at once (MPI_Abort): after an error on this rank alone, the others would wait forever in
  // the next collective. Returns only when the world is one rank.
  static void abort_all(int exit_code);

 private:
  [[maybe_unused]] bool started_ = false;  // MPI_Init was called (read only in a build with MPI)
};

// Contiguous shares of `count` items over `parts` ranks: rank r takes [offsets[r], offsets[r + 1]); the first
// count % parts ranks take one more.
std::vector<size_t> share_offsets(size_t count, int parts);

// 64-bit FNV-1a of bytes, chained through `hash` (the fingerprints ranks compare).
uint64_t fnv1a(const void* data, size_t bytes, uint64_t hash = 14695981039346656037ull);

// Every rank's `value` must equal rank 0's: otherwise a CollectiveError on every rank naming `what` and the ranks
// that differ, followed by `advice`.
void require_same_on_every_rank(uint64_t value, const std::string& what, const std::string& advice);

}  // namespace mipnerf::parallel
