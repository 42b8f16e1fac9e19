// Host-free static solver for the Nuss FE analysis: small-strain linear elasticity and geometrically
// nonlinear statics (total Lagrangian; St Venant-Kirchhoff or compressible neo-Hookean; Newton with load
// increments, optionally with a line search, automatic step control or displacement control), TET4/TET10,
// sparse Cholesky by CHOLMOD (supernodal, symbolic analysis done once per solver), OpenMP assembly.
// Units: mm, N, MPa. Errors throw pectus::InputError for bad input, pectus::TopologyError for a mesh without
// tets or with invalid, inverted or folded ones, and pectus::SolverFailure for a singular system or a Newton
// solve that does not converge (NewtonDidNotConverge) or a factor over the memory budget (ModelTooLarge).
#pragma once
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <functional>

#include <Eigen/Core>

#include "pectus/errors.h"
#include "pectus/fe/tet_mesh.h"

namespace pectus::fe {

/// The strain energy of a tissue under large displacement (solveNonlinear; the linear solve uses Hooke's
/// law for all). Every model has Hooke's law with the same E and nu as its small-strain limit, with
/// mu = E / (2 (1 + nu)), lambda = E nu / ((1 + nu)(1 - 2 nu)), bulk modulus K = E / (3 (1 - 2 nu)).
enum class MaterialModel {
  /// W = lambda/2 (tr E)^2 + mu E:E, linear in the Green-Lagrange strain E: softens under large compression
  /// (the stress falls again beyond ~42 % shortening) and lets elements invert
  StVenantKirchhoff,
  /// W = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2 (FEBio's "neo-Hookean", Bonet & Wood): W -> infinity as J -> 0
  NeoHookean,
  /// W = C10 (I1bar - 3) + (J - 1)^2 / D1, C10 = mu / 2, D1 = 2 / K, I1bar = J^(-2/3) I1 (CalculiX's and
  /// Abaqus's *HYPERELASTIC, NEO HOOKE): the form writeCalculixInp can hand to ccx unchanged
  NeoHookeanDecoupled,
};
/// "svk", "neo-hookean", "neo-hookean-ccx"; parseMaterialModel throws InputError listing them
const char* materialModelName(MaterialModel m);
MaterialModel parseMaterialModel(const std::string& name);

struct Material {
  double E = 0;   ///< Young's modulus, MPa
  double nu = 0;  ///< Poisson's ratio
  MaterialModel model = MaterialModel::StVenantKirchhoff;
};

/// Second Piola-Kirchhoff stress S and material tangent D = 2 dS/dC (Voigt 00, 11, 22, 01, 12, 02, so that
/// dS = D dE with engineering shears in dE) of a material at deformation gradient F. Returns det F; when
/// it is not positive S and D are NaN for the hyperelastic models (their energy is infinite there).
double materialResponse(const Material& m, const Eigen::Matrix3d& F, Eigen::Matrix3d& S, Eigen::Matrix<double, 6, 6>& D);

/// Young's moduli of the thesis (6.2), MPa: bone (ribs and sternum) 11.5 GPa; pectus costal cartilage
/// 12.25 MPa, half of normal cartilage (Feng et al.)
constexpr double kThesisBoneE = 11500.0, kThesisCartilageE = 12.25;

/// The tissues' materials by label (1 bone, 2 cartilage, 3 sternum, which is bone). The defaults are the
/// thesis' moduli; the Poisson ratios are literature defaults: 0.3 for cortical bone, 0.4 for costal
/// cartilage (nearly incompressible hydrated tissue).
std::map<int, Material> thesisMaterials(double nuBone = 0.3, double nuCartilage = 0.4,
                                        MaterialModel model = MaterialModel::StVenantKirchhoff,
                                        double eBone = kThesisBoneE, double eCartilage = kThesisCartilageE);

struct Dirichlet { int node; int dof; double value; };  ///< dof 0..2 = x,y,z; value in mm

struct Problem {
  const TetMesh* mesh = nullptr;
  std::map<int, Material> materials;  ///< tissue label -> material (every tissue used must be present)
  std::vector<Dirichlet> fixed;       ///< prescribed displacements (scaled with the load in Newton steps)
  std::vector<Eigen::Vector3d> force; ///< nodal forces, N (size numNodes, or empty = none)

  void fixNode(int node) { for (int d = 0; d < 3; ++d) fixed.push_back({node, d, 0.0}); }
  void addForce(int node, const Eigen::Vector3d& f);
};

/// One Newton iteration of a nonlinear solve, as NewtonOptions::onIteration reports it. Quadratic
/// convergence shows in the residual's and the correction's ratios to the iteration before (each about the
/// square of the one before, at the end of an increment).
struct NewtonIteration {
  int increment = 0;        ///< the increment, counted from 0 over the solve's converged increments
  int iteration = 0;        ///< 0: the increment's first state (the predictor's)
  double residual = 0;      ///< ||r_free||_2 at the iteration's state, N
  double reference = 0;     ///< the residual's reference max(||f_ext||_2, ||reactions||_2), N
  /// max |du| of the Newton correction computed for that residual, mm (the step taken is it times the line
  /// search's factor); at the iteration that converged, the check correction; NaN where none was computed
  double correction = 0;
};

/// One line for a Newton iteration: "increment 3, iteration 2: |r| 1.2e-02 N = 1.0e-03 of 12.3 N
/// (x1.2e-02), |du| 4.5e-03 mm (x3.4e-02)", the ratios to `before` (the iteration before in the same
/// increment; none for an increment's first)
std::string newtonIterationText(const NewtonIteration& it, const NewtonIteration* before = nullptr);

struct NewtonOptions {
  int loadSteps = 10;         ///< equal load increments
  int maxIterations = 25;     ///< per increment
  /// An increment has converged when the residual ||r_free|| <= tolResidual * max(||f_ext||, ||reactions||)
  /// and the correction the factor in hand gives for it (one back-substitution: the step modified Newton
  /// would take) has max |du| <= tolDisplacement * max |u|; under displacement control also
  /// |w . u - target| <= tolDisplacement * |target|. The state taken is the one whose residual was checked.
  double tolResidual = 1e-4;
  double tolDisplacement = 1e-5;
  /// The displacement criterion of the increments whose state the solve only passes through (neither the
  /// end nor a stop): max |du| <= tolDisplacementBetween * max |u| (tolDisplacement where that is larger).
  /// Such a state is the start of the next increment, whose iterations remove the error it carries, so
  /// the end state is as accurate as with tolDisplacement throughout; onIncrement sees these states with
  /// this accuracy. 1e-3 is CalculiX's C_n^alpha = 0.01 of the increment's change at ten increments.
  double tolDisplacementBetween = 1e-3;
  int maxCutbacks = 4;        ///< halve a failing increment at most this many times
  /// modified Newton: keep the factorisation while the residual falls at least 3x per iteration,
  /// refactorise otherwise (a factorisation costs ~20 solves on a 100k-dof TET10 model)
  bool modified = false;
  /// load factors in (0,1], ascending, every increment sequence must hit exactly (e.g. 20 N steps of a force curve)
  std::vector<double> stops;
  /// called after every converged increment with (load factor, displacements)
  std::function<void(double, const Eigen::VectorXd&)> onIncrement;
  /// called once per Newton iteration (NewtonIteration: the residual, its reference and the correction
  /// computed for it), after the correction and before the step
  std::function<void(const NewtonIteration&)> onIteration;
  /// predictor: each increment starts from the converged state extrapolated along the last increment's
  /// path (u_n + s (u_n - u_n-1), s the ratio of the steps); off: from the converged state
  bool extrapolate = true;

  /// Line search along each Newton step du: back off (a quarter each time) while the residual at
  /// u + a du is not finite (an element inverted: the neo-Hookean energy is infinite there), then secant
  /// steps on s(a) = du . r(u + a du) until |s(a)| <= lineSearchTol |s(0)| or ||r(u + a du)|| < ||r(u)||
  /// (at most lineSearchSteps residual evaluations, without the tangent; under displacement control the
  /// back-off only). Off: full steps, a non-finite residual fails the increment.
  bool lineSearch = false;
  double lineSearchTol = 0.8;
  int lineSearchSteps = 6;
  /// Automatic load-step control: after an increment converged in at most targetIterations iterations
  /// the next is 1.5x as large (up to maxStepGrowth / loadSteps), after more than 3 x targetIterations it
  /// is halved; a failing increment is halved and retried, maxCutbacks times in a row at most (without
  /// it: maxCutbacks halvings over the whole solve). The stops are still hit exactly.
  bool adaptiveSteps = false;
  int targetIterations = 8;
  double maxStepGrowth = 4.0;
};

/// Thrown by Solver::solveNonlinear when Newton does not converge after the step cut-backs (a
/// SolverFailure: the message says what to do); `loadFactor` is the load factor it could not reach.
struct NewtonDidNotConverge : SolverFailure {
  NewtonDidNotConverge(const std::string& what, double factor) : SolverFailure(what), loadFactor(factor) {}
  double loadFactor;
};

/// Thrown when the stiffness matrix's factor would not fit in the memory this process may still take
/// (found by the symbolic analysis, before the factor is allocated): the message says how to make the
/// model smaller (a SolverFailure). Never caught as a hard load step.
struct ModelTooLarge : SolverFailure {
  using SolverFailure::SolverFailure;
};

struct Result {
  Eigen::VectorXd u;          ///< nodal displacements, 3*numNodes (mm)
  std::vector<double> vonMises;   ///< per tet (MPa): small strain sigma, or Cauchy stress for nonlinear
  std::vector<double> eqStrain;   ///< per tet: ANSYS-style von Mises equivalent strain (Green-Lagrange for NL)
  Eigen::VectorXd reactions;  ///< nodal forces at the prescribed dofs (N; internal force, 3*numNodes, 0 at free dofs)
  double loadFactor = 1;      ///< the load factor of u: loadScale, or what solveControlled found
  int newtonIterations = 0;
  int increments = 0;
  int factorizations = 0;
  bool nonlinear = false;
  Eigen::Vector3d displacement(int node) const { return u.segment<3>(3 * node); }
};

/// Holds the sparsity pattern and the CHOLMOD symbolic factorisation of one (mesh, fixed dofs) pair;
/// reuse it across load cases (calibration) to skip the analysis.
class Solver {
 public:
  explicit Solver(const Problem& p);  ///< checks the problem, orders the nodes, builds the pattern of K
  ~Solver();
  Solver(const Solver&) = delete;
  Solver& operator=(const Solver&) = delete;

  /// loadScale multiplies the forces and the prescribed displacements
  Result solveLinear(double loadScale = 1.0);
  Result solveNonlinear(const NewtonOptions& opt = {}, double loadScale = 1.0);
  /// Displacement control: the load factor L of the forces is an unknown, found with u so that the
  /// weighted sum of displacements w . u (weights: 3*numNodes, e.g. 1/n along a direction at n nodes:
  /// their mean displacement along it) reaches `target`. Increments step w . u from 0 to target (the
  /// stops are fractions of the target); each Newton iteration solves the bordered system
  /// [K -f; w^T 0] by two back-substitutions with one factorisation of K. onIncrement gets (L, u); the
  /// result's loadFactor is L. Needs zero prescribed displacements (they would not scale with L) and
  /// forces with w . K^-1 f > 0; throws NewtonDidNotConverge (its loadFactor: the fraction of the
  /// target not reached) when the path cannot be followed.
  Result solveControlled(const Eigen::VectorXd& weights, double target, const NewtonOptions& opt = {});

  int numFreeDofs() const;
  double lastSolveSeconds() const { return lastFactorSeconds_; }  ///< wall time of the last factorisation

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  double lastFactorSeconds_ = 0;
};

/// Loops over tets (a colour of the assembly, the stresses) shorter than this run in one OpenMP thread
/// (default 2048): a parallel region costs a barrier, which on a busy machine waits for a descheduled
/// thread. Results do not depend on it (the sums are formed in colour order); tests set 1 to run the
/// parallel paths on small meshes.
void setMinParallelTets(int tets);
int minParallelTets();

/// Stops the threads Debian's OpenBLAS (pthreads build) starts when it is loaded. Each spins for about
/// 0.1 s of a core before it sleeps; MeshLab loads every plugin at start-up, so they would take a core
/// from the first filter a script runs, whichever plugin it is. OpenBLAS starts them again at the first
/// call that needs them. With another BLAS it does nothing.
void restBlasThreads();

inline Result solveLinear(const Problem& p) { return Solver(p).solveLinear(); }
inline Result solveNonlinear(const Problem& p, const NewtonOptions& o = {}) { return Solver(p).solveNonlinear(o); }

/// Per-tet values averaged to the nodes (volume-weighted; for TET10 the mid-edge nodes too).
std::vector<double> averageToNodes(const TetMesh& m, const std::vector<double>& perTet);

}  // namespace pectus::fe
