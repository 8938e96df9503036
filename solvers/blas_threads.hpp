// The BLAS that CHOLMOD's supernodal Cholesky and UMFPACK's multifrontal LU call on their dense blocks. When it is
// OpenBLAS (Debian's alternative to the reference BLAS), its own threads would do part of the work: on this
// project's 2-core machines they spin against the caller (measured: a third of the run in the scheduler), and a
// run's thread CPU time would not count their work.
#pragma once

namespace stepwise {

// keeps the BLAS on the calling thread, through OpenBLAS's own call where it is the BLAS loaded (looked up at run
// time: the reference BLAS has no such call); once a process, before the first factorisation
void keep_blas_on_this_thread();

}  // namespace stepwise
