// MPI ranks: the processes `mpirun -np N stepwise ...` starts, each running the same command. MPI is started
// only when a launcher started this process (its environment says so), so a serial run stays a serial
// program: no MPI start-up, no messages, the same outputs. Rank 0 writes; the others compute their share of
// each sweep and hand it over (report/sweep.hpp). MPI's own types stay in ranks.cpp.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace stepwise::ranks {

// MPI for the life of main when a launcher started the process; nothing otherwise
class Session {
 public:
  Session(int& argc, char**& argv);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;
};

int rank();  // this process's rank, 0 without mpirun
int size();  // the number of ranks, 1 without mpirun

// every rank's bytes, in rank order, on every rank (collective: every rank calls it, in the same order)
std::vector<std::string> all_gather(std::string_view mine);

// the largest of every rank's value, on every rank (collective)
double max_over_ranks(double mine);

// whether every rank says yes (collective); without mpirun, `mine`
bool all_agree(bool mine);

// for a command that runs on rank 0 alone: true on the other ranks (they have nothing to do and return at
// once); under mpirun rank 0 says so in one line, with `why`
bool idle_here(std::string_view command, std::string_view why);

// stop every rank now with this exit status (a rank that cannot go on alone: the others would wait for it)
[[noreturn]] void abort_all(int status);

// the MPI library's version ("Open MPI v4.1.4"), started or not
std::string library_version();

}  // namespace stepwise::ranks
