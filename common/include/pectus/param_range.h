// The valid range of a numeric parameter: one definition that a core's own check and the filter's
// declaration (its tool-tip and its checked accessor, common/meshlab/filter_plugin.h) both use.
// Host-free: the standard library only.
#pragma once
#include <cmath>
#include <sstream>
#include <string>

namespace pectus {

struct ParamRange {
  double lo = 0, hi = 0;
  bool loOpen = false, hiOpen = false;  ///< an open end excludes the bound itself

  /// v is a finite number inside the range
  bool contains(double v) const {
    return std::isfinite(v) && (loOpen ? v > lo : v >= lo) && (hiOpen ? v < hi : v <= hi);
  }
  /// "[lo, hi]", "(lo, hi]", ...: the bounds as an ostream prints a double by default (1e6 is "1e+06"),
  /// or as whole numbers for an integer parameter
  std::string text(bool integer = false) const {
    std::ostringstream s;
    s << (loOpen ? "(" : "[");
    if (integer)
      s << static_cast<long long>(lo) << ", " << static_cast<long long>(hi);
    else
      s << lo << ", " << hi;
    s << (hiOpen ? ")" : "]");
    return s.str();
  }
};

}  // namespace pectus
