// Cell index of a coordinate in a uniform grid, safe for any double.
#pragma once
#include <cmath>

namespace pectus {

/// floor(q) clamped to [0, n-1], computed in double first: `int(std::floor(q))` is undefined behaviour
/// when q is outside int's range (a query far from a tiny grid) or NaN. NaN gives 0.
inline int clampedCell(double q, int n) {
  const double c = std::floor(q);
  if (!(c > 0)) return 0;
  return c < double(n - 1) ? int(c) : n - 1;
}

}  // namespace pectus
