#include "pectus/fe/calibrate.h"

#include <cmath>
#include <sstream>
#include <utility>
#include <vector>

#include "pectus/errors.h"

namespace pectus::fe {

CalibrationResult calibrateForce(const std::function<double(double)>& displacement, double target,
                                 const CalibrationOptions& opt) {
  return calibrateForce([&](double f, const Observer&) { return displacement(f); }, target, opt);
}

CalibrationResult calibrateForce(const std::function<double(double, const Observer&)>& displacement, double target,
                                 const CalibrationOptions& opt) {
  if (!(target > 0)) throw InputError("The target displacement must be positive.");
  if (!(opt.initialForce > 0) || !(opt.maxForce >= opt.initialForce))
    throw InputError("Calibration: need 0 < initial force <= maximum force.");
  CalibrationResult r;
  double lo = 0, dlo = 0;                 // below target (origin)
  double hi = -1, dhi = 0;                // above target once found
  // intermediate points seen on the way (load increments) tighten the bracket
  std::vector<std::pair<double, double>> obs;  // intermediate points of the last evaluation, ascending
  const Observer observe = [&](double f, double d) {
    if (!(f > 0) || !std::isfinite(d)) return;
    obs.emplace_back(f, d);
    if (d < target - opt.tolerance && f > lo) lo = f, dlo = d;
    if (d > target + opt.tolerance && (hi < 0 || f < hi)) hi = f, dhi = d;
  };
  auto eval = [&](double f) {
    const double d = displacement(f, observe);
    if (!std::isfinite(d)) throw InputError("Calibration: the displacement is not finite at force " + std::to_string(f) + " N.");
    r.history.emplace_back(f, d);
    ++r.evaluations;
    r.force = f;
    r.displacement = d;
    return d;
  };
  double fPrev = 0, dPrev = 0;
  double f = std::min(opt.initialForce, opt.maxForce);
  while (true) {
    if (r.evaluations >= opt.maxEvaluations) {
      std::ostringstream s;
      s << "Calibration did not reach the target " << target << " mm within " << opt.maxEvaluations << " solves (last: "
        << r.force << " N -> " << r.displacement << " mm).";
      throw InputError(s.str());
    }
    obs.clear();
    const double d = eval(f);
    if (std::abs(d - target) <= opt.tolerance) return r;
    if (d <= 0 && r.evaluations == 1)
      throw InputError("Calibration: a positive force gives a displacement <= 0 along the measured direction; "
                       "check the force direction and the measured node.");
    if (d < target) {
      if (f > lo) lo = f, dlo = d;
      if (f >= opt.maxForce) {
        std::ostringstream s;
        s << "No force up to " << opt.maxForce << " N reaches the target displacement " << target << " mm (at "
          << opt.maxForce << " N: " << d << " mm). Lower the target or raise the maximum force.";
        throw InputError(s.str());
      }
    } else if (hi < 0 || f < hi) {
      hi = f, dhi = d;
    }
    // secant through the last two points (the first time: through the origin); below the target with
    // intermediate points, through the last two of them: the local slope of a stiffening curve, which
    // overshoots less than the chord from the origin undershoots
    double next = (d - dPrev) != 0 ? f + (target - d) * (f - fPrev) / (d - dPrev) : 2 * f;
    if (hi < 0 && obs.size() >= 2) {
      const auto& [f1, d1] = obs[obs.size() - 2];
      if (d - d1 > 0 && f - f1 > 0) next = f + (target - d) * (f - f1) / (d - d1);
    }
    fPrev = f, dPrev = d;
    if (hi < 0) {
      if (!(next > lo) || !std::isfinite(next)) next = 2 * lo;
      next = std::min({next, 4 * std::max(lo, f), opt.maxForce});
    } else {
      // keep inside the bracket; regula falsi on the bracket if the secant leaves it
      const double margin = 0.02 * (hi - lo);
      if (!(next > lo + margin && next < hi - margin) || !std::isfinite(next))
        next = lo + (target - dlo) * (hi - lo) / (dhi - dlo);
      if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    }
    f = next;
  }
}

}  // namespace pectus::fe
