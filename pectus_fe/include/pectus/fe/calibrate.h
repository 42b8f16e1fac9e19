// Force calibration (thesis 6.4.1): the force whose displacement matches a target (e.g. the sternal
// elevation seen on the post-operative X-ray, 34-45 mm) by a safeguarded secant search.
#pragma once
#include <functional>
#include <utility>
#include <vector>

namespace pectus::fe {

struct CalibrationOptions {
  double tolerance = 0.1;       ///< |displacement - target| <= tolerance (mm)
  double initialForce = 20.0;   ///< first trial force (N); use target / linear compliance when known
  double maxForce = 2000.0;     ///< never try more; the target is unreachable if d(maxForce) < target
  int maxEvaluations = 20;
};

struct CalibrationResult {
  double force = 0;
  double displacement = 0;
  int evaluations = 0;
  std::vector<std::pair<double, double>> history;  ///< (force, displacement) of every evaluation (NaN: did not converge)
};

/// displacement(F) must be increasing in F with displacement(0) = 0 (it is not evaluated at 0).
/// The next force interpolates F(d) through every state seen so far: inverse quadratic through the three
/// points around the target, kept inside the bracket once there is one (else linear on the bracket); before
/// that, extrapolation through the last points (secant as the fallback), at most 4 times the highest force
/// below the target. Throws pectus::SolverFailure when the target is not
/// reached up to maxForce, a displacement is not finite or maxEvaluations is exceeded, and pectus::InputError
/// for a target or forces out of range or a displacement of the wrong sign.
/// A NewtonDidNotConverge from displacement() (solver.h) is a failed evaluation: when a state observed
/// before it (Observer below) lies beyond the target, the search goes on below the failing force;
/// otherwise a SolverFailure says that no converged state reaches the target. Other exceptions propagate.
CalibrationResult calibrateForce(const std::function<double(double)>& displacement, double target,
                                 const CalibrationOptions& opt = {});

/// (force N, displacement mm) of a state passed on the way to the requested force
using Observer = std::function<void(double, double)>;
/// Same, but displacement(F, observe) may report the intermediate states it passed (e.g. the load
/// increments of a nonlinear solve): they narrow the bracket, so a stiffening curve sampled every 20 N
/// is calibrated in 2-3 solves instead of 4-6.
CalibrationResult calibrateForce(const std::function<double(double, const Observer&)>& displacement, double target,
                                 const CalibrationOptions& opt = {});

}  // namespace pectus::fe
