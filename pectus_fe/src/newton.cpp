// The Newton path of the nonlinear solves: load (or displacement) increments, each solved by Newton
// iterations, with the line search, the automatic step control, the cut-backs and the convergence test.
// The physics (the assembly, the factorisation, the stresses) is the solver's (solver_impl.h).
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

#include "pectus/errors.h"
#include "pectus/format.h"
#include "solver_impl.h"

namespace pectus::fe {

namespace {

// the Newton options must allow a path: at least one step and iteration, a usable line search and step control
void checkNewtonOptions(const NewtonOptions& opt) {
  if (opt.loadSteps < 1 || opt.maxIterations < 1) throw InputError("Newton: need at least one load step and one iteration.");
  if (opt.lineSearch && !(opt.lineSearchTol > 0 && opt.lineSearchSteps >= 1))
    throw InputError("Newton: the line search needs a tolerance > 0 and at least one step.");
  if (opt.adaptiveSteps && !(opt.targetIterations >= 1 && opt.maxStepGrowth >= 1))
    throw InputError("Newton: automatic steps need target iterations >= 1 and a maximum growth >= 1.");
}

}  // namespace

// a Newton path's state and its steps (path): increments of the load factor (or displacement fraction), each
// solved by Newton iterations from a trial state
struct Solver::Impl::NewtonPath {
  Impl& I;
  const NewtonOptions& opt;
  const double scale;
  const Eigen::VectorXd* const ctrl;
  const double dTarget;
  double& factorSeconds;
  Result res;
  Eigen::VectorXd u, fint, fintConverged;
  const Eigen::VectorXd fFree;
  const double fextNorm;
  double lam = 0, dlam;  // the converged load factor (or displacement fraction) and the next step
  const double maxStep;
  double L = 0;  // displacement control: load factor of the converged state
  int cut = 0;
  double tolD = 0;  // the displacement criterion of the increment in hand
  // the converged state before u (the predictor extrapolates through it and u, once lam > lamPrev)
  Eigen::VectorXd uPrev;
  double lamPrev = 0, LPrev = 0;
  Eigen::VectorXd b;  // displacement control: K^-1 f_ext with the factor of the path's factorisation bFactor
  int bFactor = -1;
  Eigen::VectorXd uLast;  // the last state evaluated (the failure report looks for an inverted tet there)
  std::string inversion;  // the first inverted tet met at a non-finite residual since the last converged increment

  NewtonPath(Impl& impl, const NewtonOptions& o, double s, const Eigen::VectorXd* c, double dT, double& fs)
      : I(impl), opt(o), scale(s), ctrl(c), dTarget(dT), factorSeconds(fs),
        u(Eigen::VectorXd::Zero(I.fext.size())), fintConverged(Eigen::VectorXd::Zero(I.fext.size())),
        fFree(I.freePart(I.fext)), fextNorm(fFree.norm() * std::abs(scale)), dlam(1.0 / opt.loadSteps),
        maxStep(opt.adaptiveSteps ? opt.maxStepGrowth / opt.loadSteps : 1.0) {
    res.nonlinear = true;
  }

  bool done() const { return !(lam < 1.0 - 1e-12); }  // the whole load (or displacement) is on

  // one increment: Newton iterations towards the next load factor; taken if they converge, else the step is cut
  void increment() {
    const double target = nextTarget();
    tolD = kept(target) ? opt.tolDisplacement : std::max(opt.tolDisplacement, opt.tolDisplacementBetween);
    double Lt = L;  // load factor of the trial state (displacement control)
    Eigen::VectorXd uTrial = trialStart(target, Lt);
    int it = 0;
    if (iterate(target, uTrial, Lt, it)) accept(target, uTrial, Lt, it);
    else cutBack(target);
  }

  // the increment's load factor: one step on, but not past the next stop
  double nextTarget() const {
    double target = std::min(1.0, lam + dlam);
    for (double st : opt.stops)
      if (st > lam + 1e-12 && st < target - 1e-12) { target = st; break; }
    return target;
  }

  // whether the state at load factor `target` is kept (the end or a stop), not only passed through
  bool kept(double target) const {
    if (!(target < 1.0 - 1e-12)) return true;
    return std::any_of(opt.stops.begin(), opt.stops.end(), [&](double st) { return std::abs(st - target) <= 1e-12; });
  }

  // the increment's first state: the converged one, moved along the path the last increment took in
  // proportion to the step (the predictor), with the prescribed displacements at the target (none under
  // displacement control); Lt, the load factor, extrapolated alike
  Eigen::VectorXd trialStart(double target, double& Lt) const {
    Eigen::VectorXd uTrial = u;
    if (opt.extrapolate && lam - lamPrev > 1e-12) {
      const double s = (target - lam) / (lam - lamPrev);
      uTrial += s * (u - uPrev);
      Lt = L + s * (L - LPrev);
    }
    for (size_t d = 0; d < I.freeIndex.size(); ++d)
      if (I.isConstrained[d]) uTrial(d) = ctrl ? 0.0 : target * scale * I.prescribed(d);
    return uTrial;
  }

  // the residual (free dofs) at a state: forces at load factor f minus the internal forces
  Eigen::VectorXd residual(const Eigen::VectorXd& uu, double f, bool tangent) {
    uLast = uu;
    I.assemble(uu, true, fint, tangent);
    return Eigen::VectorXd(f * fFree - I.freePart(fint));
  }
  double factorAt(double Lc, double target) const { return ctrl ? Lc : target * scale; }

  // the residual's reference: the applied forces (or, under displacement control, the load factor's) or the
  // reactions (the internal forces at the fixed dofs, after residual()), whichever is larger
  double referenceForce(double Lt, double target) const {
    double reactions = 0;
    for (size_t d = 0; d < I.freeIndex.size(); ++d)
      if (I.isConstrained[d]) reactions += fint(d) * fint(d);
    return std::max({ctrl ? std::abs(Lt) * fFree.norm() : target * fextNorm, std::sqrt(reactions), 1e-30});
  }

  // Newton iterations from uTrial (load factor Lt) at the target; true if they converged (it: their count).
  // Converged: the residual within tolResidual of its reference, and the correction the factor in hand
  // gives for it (one back-substitution, no factorisation: the step modified Newton would take) within
  // tolD of the largest displacement. The state taken is the one whose residual was checked.
  bool iterate(double target, Eigen::VectorXd& uTrial, double& Lt, int& it) {
    double lastRn = 1e300;
    for (; it <= opt.maxIterations; ++it) {
      const Eigen::VectorXd r = residual(uTrial, factorAt(Lt, target), true);
      const double ref = referenceForce(Lt, target), rn = r.norm();
      NewtonIteration rec{res.increments, it, rn, ref, std::numeric_limits<double>::quiet_NaN()};
      if (!std::isfinite(rn)) {
        report(rec);
        if (inversion.empty()) inversion = I.invertedAt(uTrial);
        return false;
      }
      const double g = ctrl ? ctrl->dot(I.freePart(uTrial)) - target * dTarget : 0.0;  // constraint violation
      const bool balanced = rn <= opt.tolResidual * ref && std::abs(g) <= opt.tolDisplacement * std::abs(dTarget);
      const bool atStart = balanced && res.factorizations == 0;  // no factor yet: balanced at the start
      if (atStart || it == opt.maxIterations) {
        report(rec);
        return atStart && converged();
      }
      const bool refactor = !opt.modified || it == 0 || !(rn < lastRn / 3);
      lastRn = rn;
      Eigen::VectorXd du;
      double dL = 0;
      const Outcome o = correction(balanced, refactor, it, uTrial, r, g, du, dL);
      if (o != Outcome::Failed) rec.correction = du.lpNorm<Eigen::Infinity>();
      report(rec);
      if (o != Outcome::Step) return o == Outcome::Converged && converged();
      const double a = opt.lineSearch ? lineSearch(uTrial, Lt, target, r, du, dL) : 1;
      for (size_t d = 0; d < I.freeIndex.size(); ++d)
        if (I.freeIndex[d] >= 0) uTrial(d) += a * du(I.freeIndex[d]);
      Lt += a * dL;
      ++res.newtonIterations;
    }
    return false;
  }

  void report(const NewtonIteration& rec) const {
    if (opt.onIteration) opt.onIteration(rec);
  }

  enum class Outcome { Failed, Converged, Step };
  // the correction du (dL) at residual r: where the state is balanced, the one the factor in hand gives
  // decides whether it has converged; else (or when that correction is too large) the Newton step
  Outcome correction(bool balanced, bool refactor, int it, const Eigen::VectorXd& uTrial, const Eigen::VectorXd& r,
                     double g, Eigen::VectorXd& du, double& dL) {
    if (balanced) {
      if (!newtonStep(false, it, uTrial, r, g, du, dL)) return Outcome::Failed;
      if (du.lpNorm<Eigen::Infinity>() <= tolD * std::max(uTrial.lpNorm<Eigen::Infinity>(), 1e-30))
        return Outcome::Converged;
      if (refactor && !newtonStep(true, it, uTrial, r, g, du, dL)) return Outcome::Failed;
      return Outcome::Step;
    }
    return newtonStep(refactor, it, uTrial, r, g, du, dL) ? Outcome::Step : Outcome::Failed;
  }

  bool converged() {
    fintConverged = fint;
    return true;
  }

  // the Newton correction du (and dL of the load factor) at residual r, constraint violation g; false
  // where there is none (the tangent is singular or not positive definite, or du is not finite)
  bool newtonStep(bool refactor, int it, const Eigen::VectorXd& uTrial, const Eigen::VectorXd& r, double g,
                  Eigen::VectorXd& du, double& dL) {
    if (refactor) try {
      I.factorize(factorSeconds);
      ++res.factorizations;
    } catch (const ModelTooLarge&) {
      throw;
    } catch (const InputError&) {
      // singular at the undeformed state: a real input problem; at a state distorted by prescribed
      // displacements (their whole increment on the boundary nodes, none yet inside) or deformed by the
      // load, the tangent lost positive definiteness (distortion, buckling, inversion): cut back
      if (it == 0 && lam == 0 && uTrial.isZero(0.0)) throw;
      return false;
    }
    du = I.chol.solve(r);
    if (ctrl) {  // bordered system: du = a + dL b, w . (u + du) = target
      if (bFactor != res.factorizations) {  // b = K^-1 f once per factor: modified Newton reuses it
        b = I.chol.solve(fFree);
        bFactor = res.factorizations;
      }
      const double wb = ctrl->dot(b);
      if (!(std::abs(wb) > 0) || !std::isfinite(wb)) return false;
      dL = (-g - ctrl->dot(du)) / wb;
      du += dL * b;
    }
    return du.allFinite();
  }

  // the step length along du from uTrial (residual r there)
  double lineSearch(const Eigen::VectorXd& uTrial, double Lt, double target, const Eigen::VectorXd& r,
                    const Eigen::VectorXd& du, double dL) {
    double a = 1;
    const double s0 = du.dot(r), sRef = std::abs(s0);
    Eigen::VectorXd uNew(uTrial.size());
    bool finite = false;
    for (int k = 0; k < opt.lineSearchSteps; ++k) {
      uNew = uTrial;
      for (size_t d = 0; d < I.freeIndex.size(); ++d)
        if (I.freeIndex[d] >= 0) uNew(d) += a * du(I.freeIndex[d]);
      const Eigen::VectorXd r1 = residual(uNew, factorAt(Lt + a * dL, target), false);
      if (!r1.allFinite()) {
        if (inversion.empty()) inversion = I.invertedAt(uNew);
        finite = false;
        a *= 0.25;
        continue;
      }
      finite = true;
      const double s1 = du.dot(r1);
      // a step that lowers the residual's norm, or leaves little of s, is taken as it is. Under
      // displacement control s is no merit function's slope (the step is driven by the constraint: the
      // secant's root is ~0 at the predictor), so only the back-off from non-finite residuals applies.
      if (ctrl || std::abs(s1) <= opt.lineSearchTol * sRef || r1.norm() < r.norm()) break;
      const double an = a * s0 / (s0 - s1);  // the root of s(a) linear through (0, s0) and (a, s1)
      if (!std::isfinite(an) || an >= a) break;  // s still as large ahead: the full step is the best guess
      a = std::max(an, 0.1 * a);
    }
    if (!finite) {  // every trial inverted an element: back off once more and let the next iteration see it
      a *= 0.25;
    }
    return a;
  }

  // the converged trial becomes the state; automatic steps grow or shrink with the iterations it took
  void accept(double target, const Eigen::VectorXd& uTrial, double Lt, int it) {
    uPrev.swap(u);
    lamPrev = lam;
    LPrev = L;
    u = uTrial;
    L = Lt;
    lam = target;
    ++res.increments;
    cut = opt.adaptiveSteps ? 0 : cut;
    inversion.clear();
    if (opt.adaptiveSteps) {
      if (it <= opt.targetIterations) dlam = std::min(1.5 * dlam, maxStep);
      else if (it > 3 * opt.targetIterations) dlam *= 0.5;
    }
    if (opt.onIncrement) opt.onIncrement(ctrl ? L : lam, u);
  }

  // halves the step; after too many cut-backs, reports why (an element that inverts, if any)
  void cutBack(double target) {
    if (++cut > opt.maxCutbacks) {
      std::string inv = I.invertedAt(uLast);
      if (inv.empty()) inv = inversion;  // an earlier trial of this increment inverted an element
      std::ostringstream s;
      s << "The nonlinear (Newton) solve did not converge at " << (ctrl ? "displacement fraction " : "load factor ") << target
        << " after " << opt.maxCutbacks << (opt.adaptiveSteps ? " step cut-backs in a row" : " step cut-backs") << ": ";
      if (!inv.empty())
        s << "an element inverts: " << inv
          << ". The load is too large for the model there; reduce the force or refine the mesh there.";
      else
        s << "the load is too large for the model (instability or inverted elements); "
             "reduce the force, use more load steps or check the boundary conditions.";
      throw NewtonDidNotConverge(s.str(), target);
    }
    dlam *= 0.5;
  }

  // the converged state, its reactions (the internal forces at the fixed dofs) and stresses
  Result result() {
    res.u = u;
    res.loadFactor = ctrl ? L : scale;
    res.reactions = Eigen::VectorXd::Zero(I.fext.size());
    for (size_t d = 0; d < I.freeIndex.size(); ++d)
      if (I.isConstrained[d]) res.reactions(d) = fintConverged(d);
    I.stresses(res.u, true, res);
    return res;
  }
};

std::string newtonIterationText(const NewtonIteration& it, const NewtonIteration* before) {
  const auto ratio = [](double now, double was) {
    return was > 0 && std::isfinite(now) ? " (x" + scientificText(now / was) + ")" : std::string();
  };
  std::string s = "increment " + std::to_string(it.increment + 1) + ", iteration " + std::to_string(it.iteration) +
                  ": |r| " + scientificText(it.residual) + " N = " + scientificText(it.residual / it.reference) + " of " +
                  significantText(it.reference, 3) + " N";
  if (before) s += ratio(it.residual, before->residual);
  s += ", |du| " + (std::isfinite(it.correction) ? scientificText(it.correction) + " mm" : std::string("none"));
  if (before) s += ratio(it.correction, before->correction);
  return s;
}

// Newton with load increments (ctrl null: load factor target * scale on the forces and prescribed
// displacements) or displacement control (ctrl: free-dof weights w, w . u stepped to target; the load
// factor is the extra unknown of a bordered system)
Result Solver::Impl::path(const NewtonOptions& opt, double scale, const Eigen::VectorXd* ctrl, double dTarget,
                          double& factorSeconds) {
  checkNewtonOptions(opt);
  NewtonPath np(*this, opt, scale, ctrl, dTarget, factorSeconds);
  while (!np.done()) np.increment();
  return np.result();
}

}  // namespace pectus::fe
