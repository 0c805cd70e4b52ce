// The process's world of ranks: MPI when built in and launched by mpirun, else one rank.
#include "parallel/world.hpp"

#include <cstdlib>

#ifdef MIPNERF_HAVE_MPI
#include <mpi.h>
#endif

namespace mipnerf::parallel {
namespace {

World g_world;

int env_int(const char* name, int fallback) {
  const char* value = std::getenv(name);
  if (value == nullptr || *value == '\0') return fallback;
  char* end = nullptr;
  const long parsed = std::strtol(value, &end, 10);
  return (*end == '\0' && parsed >= 0) ? static_cast<int>(parsed) : fallback;
}

}  // namespace

const World& world() { return g_world; }

int launcher_rank() { return env_int("OMPI_COMM_WORLD_RANK", env_int("PMI_RANK", 0)); }

int launcher_world_size() { return env_int("OMPI_COMM_WORLD_SIZE", env_int("PMI_SIZE", 1)); }

std::vector<size_t> share_offsets(size_t count, int parts) {
  if (parts < 1) throw Error("share_offsets: " + std::to_string(parts) + " parts; at least 1 is needed");
  const auto n = static_cast<size_t>(parts);
  std::vector<size_t> offsets(n + 1, 0);
  for (size_t r = 0; r < n; ++r) offsets[r + 1] = offsets[r] + count / n + (r < count % n ? 1 : 0);
  return offsets;
}

uint64_t fnv1a(const void* data, size_t bytes, uint64_t hash) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < bytes; ++i) {
    hash ^= p[i];
    hash *= 1099511628211ull;
  }
  return hash;
}

void require_same_on_every_rank(uint64_t value, const std::string& what, const std::string& advice) {
  const std::vector<uint64_t> values = world().all_gather(value);
  std::string differing;
  for (size_t r = 1; r < values.size(); ++r) {
    if (values[r] != values[0]) differing += (differing.empty() ? "" : ", ") + std::to_string(r);
  }
  if (!differing.empty()) {
    throw CollectiveError("the ranks disagree on " + what + ": rank(s) " + differing + " differ from rank 0; " +
                          advice);
  }
}

#ifdef MIPNERF_HAVE_MPI

namespace {

bool launched_by_mpi() {
  return std::getenv("OMPI_COMM_WORLD_SIZE") != nullptr || std::getenv("PMI_SIZE") != nullptr ||
         std::getenv("PMIX_RANK") != nullptr;
}

}  // namespace

void World::sum_in_place(float* values, size_t count) const {
  if (size_ == 1 || count == 0) return;
  // Chunks of at most 2^30 elements: MPI counts are ints.
  for (size_t done = 0; done < count; done += (size_t{1} << 30)) {
    const size_t n = std::min(count - done, size_t{1} << 30);
    MPI_Allreduce(MPI_IN_PLACE, values + done, static_cast<int>(n), MPI_FLOAT, MPI_SUM, MPI_COMM_WORLD);
  }
}

void World::sum_in_place(double* values, size_t count) const {
  if (size_ == 1 || count == 0) return;
  MPI_Allreduce(MPI_IN_PLACE, values, static_cast<int>(count), MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
}

std::vector<uint64_t> World::all_gather(uint64_t value) const {
  std::vector<uint64_t> out(static_cast<size_t>(size_), value);
  if (size_ > 1) {
    MPI_Allgather(&value, 1, MPI_UINT64_T, out.data(), 1, MPI_UINT64_T, MPI_COMM_WORLD);
  }
  return out;
}

void World::broadcast(std::string& text) const {
  if (size_ == 1) return;
  unsigned long long length = text.size();
  MPI_Bcast(&length, 1, MPI_UNSIGNED_LONG_LONG, 0, MPI_COMM_WORLD);
  text.resize(static_cast<size_t>(length));
  if (length > 0) MPI_Bcast(text.data(), static_cast<int>(length), MPI_CHAR, 0, MPI_COMM_WORLD);
}

void World::all_gather_segments(float* data, const std::vector<size_t>& offsets) const {
  if (offsets.size() != static_cast<size_t>(size_) + 1) {
    throw Error("all_gather_segments: " + std::to_string(offsets.size()) + " offsets for " + std::to_string(size_) +
                " ranks; expected one more than the ranks");
  }
  if (size_ == 1) return;
  std::vector<int> counts(static_cast<size_t>(size_)), displacements(static_cast<size_t>(size_));
  for (size_t r = 0; r < counts.size(); ++r) {
    if (offsets[r + 1] > (size_t{1} << 31) - 1) throw Error("all_gather_segments: more than 2^31 elements");
    counts[r] = static_cast<int>(offsets[r + 1] - offsets[r]);
    displacements[r] = static_cast<int>(offsets[r]);
  }
  MPI_Allgatherv(MPI_IN_PLACE, 0, MPI_DATATYPE_NULL, data, counts.data(), displacements.data(), MPI_FLOAT,
                 MPI_COMM_WORLD);
}

void World::barrier() const {
  if (size_ > 1) MPI_Barrier(MPI_COMM_WORLD);
}

Session::Session(int* argc, char*** argv) {
  if (!launched_by_mpi()) return;
  MPI_Init(argc, argv);
  started_ = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &g_world.rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &g_world.size_);
  MPI_Comm local;
  MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &local);
  MPI_Comm_rank(local, &g_world.local_rank_);
  MPI_Comm_size(local, &g_world.local_size_);
  MPI_Comm_free(&local);
}

Session::~Session() {
  if (started_) MPI_Finalize();
}

void Session::abort_all(int exit_code) {
  if (g_world.size_ > 1) MPI_Abort(MPI_COMM_WORLD, exit_code);
}

#else  // one rank: every collective is the identity

void World::sum_in_place(float*, size_t) const {}
void World::sum_in_place(double*, size_t) const {}
std::vector<uint64_t> World::all_gather(uint64_t value) const { return {value}; }
void World::broadcast(std::string&) const {}
void World::all_gather_segments(float*, const std::vector<size_t>& offsets) const {
  if (offsets.size() != 2) throw Error("all_gather_segments: expected 2 offsets for one rank");
}
void World::barrier() const {}

Session::Session(int*, char***) {
  const int launched = launcher_world_size();
  if (launched > 1) {
    // Each copy would train alone and overwrite the others' outputs: refuse, once (the launcher's rank 0 says it).
    const std::string message =
        "this mipnerf-cl was built without MPI, but an MPI launcher started " + std::to_string(launched) +
        " copies of it, which would each run alone and overwrite each other's outputs; install libopenmpi-dev "
        "(scripts/install-deps.sh) and rebuild, or run it without mpirun";
    if (launcher_rank() == 0) throw Error(message);
    throw CollectiveError(message);
  }
}

Session::~Session() = default;

void Session::abort_all(int) {}

#endif

}  // namespace mipnerf::parallel
