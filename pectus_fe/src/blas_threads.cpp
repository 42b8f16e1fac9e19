// The BLAS threads: how many CHOLMOD's factorisation gets, and their rest between filters.
#include "blas_threads.h"

#include <algorithm>
#include <cstdlib>

#include <dlfcn.h>
#include <omp.h>

#include "pectus/fe/solver.h"

namespace pectus::fe {

namespace {

// CHOLMOD's supernodal factorisation calls the BLAS for its dense blocks. Debian's OpenBLAS (pthreads
// build) starts its own busy-waiting threads for every call; beside this program's OpenMP threads, or on a
// machine whose cores are taken by other jobs, they oversubscribe the cores and a factorisation of the rib
// cage's systems (small supernodes, ~1e8-1e9 flops) is 5-10x slower than on one BLAS thread (a 127k-dof
// cage: 2.94 s against 0.27 s). So the BLAS gets one thread for small factorisations and
// OpenMP's thread count from kBlasThreadFlops on (the long cantilever benchmark: 2e11 flops). The call is
// looked up at run time (the BLAS behind libblas.so.3 is chosen by Debian's alternatives; the reference
// BLAS has no threads to set). PECTUS_BLAS_THREADS=n forces n.
constexpr double kBlasThreadFlops = 2e10;

// an OpenBLAS function in the BLAS this process has loaded; null for another BLAS
void* openBlasFunction(const char* name) {
  for (const char* lib : {"libopenblas.so.0", "libblas.so.3", "libopenblas.so"})
    if (void* h = dlopen(lib, RTLD_LAZY | RTLD_NOLOAD))
      if (void* f = dlsym(h, name)) return f;
  return dlsym(RTLD_DEFAULT, name);
}

}  // namespace

void setBlasThreads(double flops) {
  using SetThreads = void (*)(int);
  static const auto set = reinterpret_cast<SetThreads>(openBlasFunction("openblas_set_num_threads"));
  if (!set) return;
  int n = flops >= kBlasThreadFlops ? omp_get_max_threads() : 1;
  if (const char* e = std::getenv("PECTUS_BLAS_THREADS")) n = std::max(1, std::atoi(e));
  set(n);
}

void restBlasThreads() {
  using Shutdown = int (*)();
  if (const auto shutdown = reinterpret_cast<Shutdown>(openBlasFunction("blas_thread_shutdown_"))) shutdown();
}

}  // namespace pectus::fe
