// Numbers as text, the one way every Log line, message and file of the project writes them: in the C locale
// (a decimal point whatever the user's locale), with a fixed number of decimals or of significant digits.
#pragma once
#include <locale>
#include <sstream>
#include <string>

namespace pectus {

namespace detail {
/// v in the C locale with the stream's float format `format` (none: printf's %g) and `precision`
inline std::string numberText(double v, std::ios::fmtflags format, int precision) {
  std::ostringstream s;
  s.imbue(std::locale::classic());
  s.setf(format, std::ios::floatfield);
  s.precision(precision);
  s << v;
  return s.str();
}
}  // namespace detail

/// v with `decimals` digits after the point: fixedText(12.3, 2) = "12.30"
inline std::string fixedText(double v, int decimals) { return detail::numberText(v, std::ios::fixed, decimals); }

/// v with at most `digits` significant digits, as printf's %g: significantText(0.012345, 3) = "0.0123",
/// significantText(123456, 3) = "1.23e+05"
inline std::string significantText(double v, int digits = 6) {
  return detail::numberText(v, std::ios::fmtflags(), digits);
}

/// v in scientific notation with `decimals` digits after the point: scientificText(0.012345, 1) = "1.2e-02"
inline std::string scientificText(double v, int decimals = 1) {
  return detail::numberText(v, std::ios::scientific, decimals);
}

}  // namespace pectus
