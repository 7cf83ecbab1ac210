#pragma once
// OpenBLAS (Debian's default BLAS, pthread build) keeps its worker threads spinning on sched_yield
// for a while after every call. Between the many small BLAS calls of CHOLMOD's coarse solves inside
// a threaded CG, those spinners take the cores from the CG's own threads. This guard runs BLAS on
// the calling thread for its lifetime, then restores the previous thread count. With another BLAS
// (no openblas_set_num_threads symbol) it does nothing.

namespace repose {

class SingleThreadedBlas {
 public:
  SingleThreadedBlas();
  ~SingleThreadedBlas();
  SingleThreadedBlas(const SingleThreadedBlas&) = delete;
  SingleThreadedBlas& operator=(const SingleThreadedBlas&) = delete;

 private:
  int previous_ = 0;  ///< OpenBLAS's thread count before, 0 when OpenBLAS is not the BLAS
};

}  // namespace repose
