// The memory a solve may take: a model whose Cholesky factor would not fit is refused before the factor is
// allocated.
#pragma once

namespace pectus::fe {

/// Bytes a new allocation can take without swapping or the kernel's out-of-memory killer: the kernel's
/// MemAvailable, bounded by the process' address-space limit (ulimit -v) and by PECTUS_FE_MEMORY_GB when
/// set (a share of a machine that runs other jobs). 0 if none is known.
double availableBytes();

/// Throws ModelTooLarge, saying what to change, when a factor of factorEntries doubles (of a system of
/// freeDofs unknowns) does not fit in the memory left
void requireFactorFits(double factorEntries, int freeDofs);

}  // namespace pectus::fe
