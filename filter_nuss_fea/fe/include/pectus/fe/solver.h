// Host-free static solver for the Nuss FE analysis: small-strain linear elasticity and geometrically
// nonlinear statics (total Lagrangian, St Venant-Kirchhoff, Newton with load increments), TET4/TET10,
// sparse Cholesky by CHOLMOD (supernodal, symbolic analysis done once per solver), OpenMP assembly.
// Units: mm, N, MPa. Errors (singular system, non-converged Newton, bad input) throw pectus::InputError.
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

struct Material {
  double E = 0;   ///< Young's modulus, MPa
  double nu = 0;  ///< Poisson's ratio
};

/// Materials of the thesis (6.2): bone (ribs and sternum) E = 11.5 GPa, pectus costal cartilage
/// E = 12.25 MPa (half of normal cartilage, Feng et al.). Poisson ratios are literature defaults:
/// 0.3 for cortical bone, 0.4 for costal cartilage (nearly incompressible hydrated tissue).
std::map<int, Material> thesisMaterials(double nuBone = 0.3, double nuCartilage = 0.4);

struct Dirichlet { int node; int dof; double value; };  ///< dof 0..2 = x,y,z; value in mm

struct Problem {
  const TetMesh* mesh = nullptr;
  std::map<int, Material> materials;  ///< tissue label -> material (every tissue used must be present)
  std::vector<Dirichlet> fixed;       ///< prescribed displacements (scaled with the load in Newton steps)
  std::vector<Eigen::Vector3d> force; ///< nodal forces, N (size numNodes, or empty = none)

  void fixNode(int node) { for (int d = 0; d < 3; ++d) fixed.push_back({node, d, 0.0}); }
  void addForce(int node, const Eigen::Vector3d& f);
};

struct NewtonOptions {
  int loadSteps = 10;         ///< equal load increments
  int maxIterations = 25;     ///< per increment
  double tolResidual = 1e-8;  ///< ||r_free|| <= tolResidual * max(||f_ext||, ||reactions||, 1e-12)
  double tolDisplacement = 1e-8;  ///< and ||du|| <= tolDisplacement * ||u||
  int maxCutbacks = 4;        ///< halve a failing increment at most this many times
  /// modified Newton: keep the factorisation while the residual falls at least 3x per iteration,
  /// refactorise otherwise (a factorisation costs ~20 solves on a 100k-dof TET10 model)
  bool modified = false;
  /// load factors in (0,1], ascending, every increment sequence must hit exactly (e.g. 20 N steps of a force curve)
  std::vector<double> stops;
  /// called after every converged increment with (load factor, displacements)
  std::function<void(double, const Eigen::VectorXd&)> onIncrement;
};

/// Thrown by Solver::solveNonlinear when Newton does not converge after the step cut-backs (an
/// InputError: the message says what to do); `loadFactor` is the load factor it could not reach.
struct NewtonDidNotConverge : InputError {
  NewtonDidNotConverge(const std::string& what, double factor) : InputError(what), loadFactor(factor) {}
  double loadFactor;
};

struct Result {
  Eigen::VectorXd u;          ///< nodal displacements, 3*numNodes (mm)
  std::vector<double> vonMises;   ///< per tet (MPa): small strain sigma, or Cauchy stress for nonlinear
  std::vector<double> eqStrain;   ///< per tet: ANSYS-style von Mises equivalent strain (Green-Lagrange for NL)
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

inline Result solveLinear(const Problem& p) { return Solver(p).solveLinear(); }
inline Result solveNonlinear(const Problem& p, const NewtonOptions& o = {}) { return Solver(p).solveNonlinear(o); }

/// Per-tet values averaged to the nodes (volume-weighted; for TET10 the mid-edge nodes too).
std::vector<double> averageToNodes(const TetMesh& m, const std::vector<double>& perTet);

}  // namespace pectus::fe
