// The BLAS threads under CHOLMOD's supernodal factorisation (restBlasThreads in solver.h stops them).
#pragma once

namespace pectus::fe {

/// The BLAS gets one thread for a factorisation of fewer than 2e10 flops, OpenMP's thread count from
/// there on; PECTUS_BLAS_THREADS=n forces n. Nothing for a BLAS other than OpenBLAS.
void setBlasThreads(double flops);

}  // namespace pectus::fe
