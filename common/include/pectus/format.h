// Numbers as text, the one way every Log line, message and file of the project writes them: in the C locale
// (a decimal point whatever the user's locale), with a fixed number of decimals or of significant digits.
#pragma once
#include <locale>
#include <sstream>
#include <string>

namespace pectus {

/// v with `decimals` digits after the point: fixedText(12.3, 2) = "12.30"
inline std::string fixedText(double v, int decimals) {
  std::ostringstream s;
  s.imbue(std::locale::classic());
  s.setf(std::ios::fixed);
  s.precision(decimals);
  s << v;
  return s.str();
}

/// v with at most `digits` significant digits, as printf's %g: significantText(0.012345, 3) = "0.0123",
/// significantText(123456, 3) = "1.23e+05"
inline std::string significantText(double v, int digits = 6) {
  std::ostringstream s;
  s.imbue(std::locale::classic());
  s.precision(digits);
  s << v;
  return s.str();
}

/// v in scientific notation with `decimals` digits after the point: scientificText(0.012345, 1) = "1.2e-02"
inline std::string scientificText(double v, int decimals = 1) {
  std::ostringstream s;
  s.imbue(std::locale::classic());
  s.setf(std::ios::scientific);
  s.precision(decimals);
  s << v;
  return s.str();
}

}  // namespace pectus
