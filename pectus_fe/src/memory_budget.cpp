// The memory budget of a solve: what the machine and the process' limits leave, and the factor's share of it.
#include "memory_budget.h"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include <sys/resource.h>
#include <unistd.h>

#include "pectus/fe/solver.h"

namespace pectus::fe {

double availableBytes() {
  double avail = 0;
  std::ifstream meminfo("/proc/meminfo");
  for (std::string key; meminfo >> key;) {
    double kb = 0;
    meminfo >> kb;
    meminfo.ignore(64, '\n');
    if (key == "MemAvailable:") {
      avail = kb * 1024.0;
      break;
    }
  }
  if (!(avail > 0)) avail = double(::sysconf(_SC_AVPHYS_PAGES)) * double(::sysconf(_SC_PAGESIZE));
  rlimit as{};
  if (::getrlimit(RLIMIT_AS, &as) == 0 && as.rlim_cur != RLIM_INFINITY) avail = std::min(avail, double(as.rlim_cur));
  if (const char* e = std::getenv("PECTUS_FE_MEMORY_GB"))
    if (const double gb = std::atof(e); gb > 0) avail = avail > 0 ? std::min(avail, gb * 1e9) : gb * 1e9;
  return avail;
}

namespace {
// The symbolic analysis knows the size of the Cholesky factor before any of it is allocated: a model
// whose factor does not fit in the memory left is refused here, with what to change, instead of being
// killed by the operating system later in the solve. The factor may take half of what is available:
// the tangent matrix, its element blocks, the Newton vectors and the results need the rest.
constexpr double kFactorShareOfMemory = 0.5;
}  // namespace

void requireFactorFits(double factorEntries, int freeDofs) {
  const double need = factorEntries * sizeof(double) / kFactorShareOfMemory, avail = availableBytes();
  if (!(avail > 0) || need <= avail) return;
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(1);
  s << "The FE model is too large for the memory of this machine: its stiffness matrix (" << freeDofs
    << " free unknowns) needs about " << need / 1e9 << " GB to factorise and solve, and " << avail / 1e9
    << " GB are available. Make fewer, larger tetrahedra: a larger edge length of the cage surface, a maximum tet "
       "volume, tet quality 0 (no refinement), or TET4 elements.";
  throw ModelTooLarge(s.str());
}

}  // namespace pectus::fe
