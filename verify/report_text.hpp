// Number formatting of verify's text reports (compressed tables, parallax). Internal to verify/.
#pragma once

#include <sstream>
#include <string>

namespace clothbake::verify {

// v with `digits` digits after the point.
inline std::string fixed_text(double v, int digits) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(digits);
  s << v;
  return s.str();
}

// v as given (thresholds such as 1e-07 or 0.01), not rounded to a fixed number of digits.
inline std::string general_text(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace clothbake::verify
