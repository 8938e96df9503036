// What the MPI code shares (run/ranks.cpp, solvers/distributed_wave.cpp): a failed call said with its name,
// code and MPI's text for it. No MPI type here: a call's return code is an int.
#pragma once

namespace stepwise {

// throws std::runtime_error "CALL failed with code C: TEXT" unless code is MPI_SUCCESS
void mpi_check(int code, const char* call);

}  // namespace stepwise
