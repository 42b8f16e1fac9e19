#include "pectus/fe/calibrate.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>
#include <vector>

#include "pectus/errors.h"
#include "pectus/fe/solver.h"

namespace pectus::fe {

CalibrationResult calibrateForce(const std::function<double(double)>& displacement, double target,
                                 const CalibrationOptions& opt) {
  return calibrateForce([&](double f, const Observer&) { return displacement(f); }, target, opt);
}

namespace {

// The next trial force from every state seen so far (all on the one force-displacement curve, which
// starts at the origin): inverse quadratic interpolation F(d) through the three points around the
// target (the bracketing pair and its nearer neighbour), or extrapolation through the last three when
// nothing is above the target yet; with only two points near the target (or the origin as the third),
// the secant through them. Safeguards: inside the bracket (else linear interpolation on it), or beyond
// the highest force below the target and at most 4 times it.
double nextForce(std::vector<std::pair<double, double>> pts, double target, double maxForce, bool increments) {
  std::sort(pts.begin(), pts.end());
  // keep a strictly increasing curve (drop repeats and points that break monotonicity)
  std::vector<std::pair<double, double>> c;
  for (const auto& p : pts)
    if (c.empty() || (p.first > c.back().first * (1 + 1e-12) && p.second > c.back().second)) c.push_back(p);
  std::size_t hi = 0;
  while (hi < c.size() && c[hi].second < target) ++hi;
  const std::size_t lo = hi - 1;  // c[0] is the origin, below any positive target
  auto quad = [&](std::size_t a) {  // F at the target through c[a], c[a+1], c[a+2]
    double F = 0;
    for (std::size_t i = a; i < a + 3; ++i) {
      double w = c[i].first;
      for (std::size_t j = a; j < a + 3; ++j)
        if (j != i) w *= (target - c[j].second) / (c[i].second - c[j].second);
      F += w;
    }
    return F;
  };
  if (hi < c.size()) {  // bracketed by c[lo] < target < c[hi]
    const auto& [fl, dl] = c[lo];
    const auto& [fh, dh] = c[hi];
    double F = fl + (target - dl) * (fh - fl) / (dh - dl);
    // the third point: the nearer neighbour of the bracket (not the origin: far from the target, it
    // carries the curve's global shape, not its local one)
    const bool below = lo >= 2 && (hi + 1 >= c.size() || target - c[lo - 1].second < c[hi + 1].second - target);
    if (below || hi + 1 < c.size()) {
      const double q = quad(below ? lo - 1 : lo);
      if (std::isfinite(q) && q > fl && q < fh) F = q;
    }
    return F;
  }
  const double fl = c.back().first;
  double F = -1;
  if (c.size() >= 4) F = quad(c.size() - 3);  // the last three, the origin not among them
  if (!(F > fl) || !std::isfinite(F)) {  // secant through the last two
    const auto& [f1, d1] = c[c.size() - 2];
    F = fl + (target - c.back().second) * (fl - f1) / (c.back().second - d1);
  }
  if (!(F > fl) || !std::isfinite(F)) F = 2 * fl;
  // extrapolation falls short on a stiffening curve, and each short solve only creeps closer; aiming
  // kOvershoot times as far makes the next solve pass the target, so its increments bracket it tightly
  // and the one after lands by interpolation
  // (only when the solves report their increments: a plain evaluation gives no bracket on the way)
  constexpr double kOvershoot = 1.5;
  if (increments) F = fl + kOvershoot * (F - fl);
  return std::min({F, 4 * fl, maxForce});
}

}  // namespace

CalibrationResult calibrateForce(const std::function<double(double, const Observer&)>& displacement, double target,
                                 const CalibrationOptions& opt) {
  if (!(target > 0)) throw InputError("The target displacement must be positive.");
  if (!(opt.initialForce > 0) || !(opt.maxForce >= opt.initialForce))
    throw InputError("Calibration: need 0 < initial force <= maximum force.");
  CalibrationResult r;
  std::vector<std::pair<double, double>> seen{{0.0, 0.0}};  // every state passed: evaluations and increments
  const Observer observe = [&](double f, double d) {
    if (f > 0 && std::isfinite(d)) seen.emplace_back(f, d);
  };
  double f = std::min(opt.initialForce, opt.maxForce);
  while (true) {
    if (r.evaluations >= opt.maxEvaluations) {
      std::ostringstream s;
      s << "Calibration did not reach the target " << target << " mm within " << opt.maxEvaluations << " solves (last: "
        << r.force << " N -> " << r.displacement << " mm).";
      throw SolverFailure(s.str());
    }
    double d = 0;
    try {
      d = displacement(f, observe);
    } catch (const NewtonDidNotConverge& e) {
      // the states passed before the failure are on the curve: if one is beyond the target, the target
      // lies between them and the next force comes from them (below the failing force); otherwise no
      // converged state reaches it
      ++r.evaluations;
      r.history.emplace_back(f, std::nan(""));
      const auto best = std::max_element(seen.begin(), seen.end(), [](const auto& a, const auto& b) { return a.second < b.second; });
      if (best->second < target) {
        std::ostringstream s;
        s << "No converged state reaches the target displacement " << target << " mm: the nonlinear solve stops converging at "
          << e.loadFactor * f << " N (" << e.what() << ") and the largest displacement reached is " << best->second << " mm at "
          << best->first << " N. Lower the target, or check the model where it deforms most (an element inverting at the load).";
        throw SolverFailure(s.str());
      }
      f = nextForce(seen, target, opt.maxForce, true);
      continue;
    }
    if (!std::isfinite(d)) throw SolverFailure("Calibration: the displacement is not finite at force " + std::to_string(f) + " N.");
    r.history.emplace_back(f, d);
    ++r.evaluations;
    r.force = f;
    r.displacement = d;
    seen.emplace_back(f, d);
    if (std::abs(d - target) <= opt.tolerance) return r;
    if (d <= 0 && r.evaluations == 1)
      throw InputError("Calibration: a positive force gives a displacement <= 0 along the measured direction; "
                       "check the force direction and the measured node.");
    if (d < target && f >= opt.maxForce) {
      std::ostringstream s;
      s << "No force up to " << opt.maxForce << " N reaches the target displacement " << target << " mm (at " << opt.maxForce
        << " N: " << d << " mm). Lower the target or raise the maximum force.";
      throw SolverFailure(s.str());
    }
    f = nextForce(seen, target, opt.maxForce, seen.size() > std::size_t(2 * r.evaluations + 1));
  }
}

}  // namespace pectus::fe
