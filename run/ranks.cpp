#include "run/ranks.hpp"

#include "solvers/mpi_support.hpp"

#include <mpi.h>

#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

namespace stepwise::ranks {

namespace {

bool started = false;
int my_rank = 0, world_size = 1;

// a launcher's environment: Open MPI's mpirun, or the PMI/PMIx of MPICH, Slurm's srun and others
bool launched() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"})
    if (std::getenv(name)) return true;
  return false;
}


}  // namespace

Session::Session(int& argc, char**& argv) {
  if (!launched()) return;
  // the sweeps' threads never call MPI: the calling thread does, between sweeps
  int provided = 0;
  mpi_check(MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
  started = true;
  MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
  mpi_check(MPI_Comm_rank(MPI_COMM_WORLD, &my_rank), "MPI_Comm_rank");
  mpi_check(MPI_Comm_size(MPI_COMM_WORLD, &world_size), "MPI_Comm_size");
}

Session::~Session() {
  if (started) MPI_Finalize();
}

int rank() { return my_rank; }
int size() { return world_size; }

std::vector<std::string> all_gather(std::string_view mine) {
  if (world_size == 1) return {std::string(mine)};
  if (mine.size() > static_cast<size_t>(INT32_MAX)) throw std::runtime_error(fmt::format("rank {}: {} bytes of results, more than one MPI message takes", my_rank, mine.size()));
  const int length = static_cast<int>(mine.size());
  std::vector<int> lengths(static_cast<size_t>(world_size)), offsets(static_cast<size_t>(world_size));
  mpi_check(MPI_Allgather(&length, 1, MPI_INT, lengths.data(), 1, MPI_INT, MPI_COMM_WORLD), "MPI_Allgather");
  long total = 0;
  for (int r = 0; r < world_size; ++r) {
    offsets[static_cast<size_t>(r)] = static_cast<int>(total);
    total += lengths[static_cast<size_t>(r)];
  }
  if (total > INT32_MAX) throw std::runtime_error(fmt::format("{} bytes of results from {} ranks, more than one MPI message takes", total, world_size));
  std::string all(static_cast<size_t>(total), '\0');
  mpi_check(MPI_Allgatherv(mine.data(), length, MPI_BYTE, all.data(), lengths.data(), offsets.data(), MPI_BYTE, MPI_COMM_WORLD), "MPI_Allgatherv");
  std::vector<std::string> out;
  for (int r = 0; r < world_size; ++r) out.push_back(all.substr(static_cast<size_t>(offsets[static_cast<size_t>(r)]), static_cast<size_t>(lengths[static_cast<size_t>(r)])));
  return out;
}

double max_over_ranks(double mine) {
  if (world_size == 1) return mine;
  double all = 0;
  mpi_check(MPI_Allreduce(&mine, &all, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD), "MPI_Allreduce");
  return all;
}

bool all_agree(bool mine) {
  if (world_size == 1) return mine;
  int yes = mine ? 1 : 0, all = 0;
  mpi_check(MPI_Allreduce(&yes, &all, 1, MPI_INT, MPI_LAND, MPI_COMM_WORLD), "MPI_Allreduce");
  return all != 0;
}

bool idle_here(std::string_view command, std::string_view why) {
  if (world_size == 1) return false;
  if (my_rank == 0)
    std::fputs(fmt::format("stepwise: {}: runs on rank 0 alone ({}); {} idle\n", command, why,
                           world_size == 2 ? std::string("rank 1") : fmt::format("ranks 1-{}", world_size - 1)).c_str(), stderr);
  return my_rank != 0;
}

void abort_all(int status) {
  if (started) MPI_Abort(MPI_COMM_WORLD, status);
  std::exit(status);
}

std::string library_version() {
  // one of the calls MPI allows before MPI_Init
  char text[MPI_MAX_LIBRARY_VERSION_STRING];
  int length = 0;
  MPI_Get_library_version(text, &length);
  std::string v(text, static_cast<size_t>(length));
  if (const auto end = v.find_first_of(",\n"); end != std::string::npos) v.resize(end);
  return v;
}

}  // namespace stepwise::ranks
