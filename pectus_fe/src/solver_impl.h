// The state of a Solver (solver.h) and its steps, shared by the solver's units: the setup (setup.cpp), the
// assembly (assembly.cpp), the factorisation (sparse_cholesky.cpp), the Newton path (newton.cpp) and the solves and
// stresses (solver.cpp).
#pragma once
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Sparse>

#include "sparse_cholesky.h"
#include "element.h"
#include "pectus/fe/solver.h"

namespace pectus::fe {

constexpr int kChunkTets = 256;  // the assembly's unit of work: consecutive tets of the dof order (colorChunks)

struct Solver::Impl {
  Problem p;
  const TetMesh* m = nullptr;
  int nen = 4;
  std::vector<int> freeIndex;                 // per dof: free index or -1
  std::vector<const Material*> mat;           // per tet
  std::vector<const Eigen::Matrix<double, 6, 6>*> D;  // per tet, into Dby (a pointer, not a 288-byte copy)
  std::map<int, Eigen::Matrix<double, 6, 6>> Dby;
  Eigen::VectorXd fext;                        // full, 3n
  Eigen::VectorXd prescribed;                  // full, 3n (0 for free dofs)
  std::vector<char> isConstrained;
  Eigen::SparseMatrix<double> K;               // free x free, lower triangle
  Cholmod chol;
  bool analysed = false;
  std::vector<std::vector<int>> colors;        // chunks of tetOrder by colour (colorChunks), for the assembly
  std::vector<int> tetOrder;                   // the tets by their first node in the dof order
  bool orderByNodes = true;                    // PECTUS_FE_ORDERING=amd|metis|nesdis: CHOLMOD orders the dofs
  double orderSeconds = 0;                     // the node ordering's time (verbose line)

  int nFree = 0;
  ReferenceTet ref;  // the element's quadrature rule and shape derivatives

  Impl();

  // --- the problem's setup (Solver's constructor), step by step (setup.cpp; the pattern: assembly.cpp) ---
  void checkTets() const;
  void bindMaterials(const Problem& prob);
  void setLoads(const Problem& prob);
  void nodeAdjacency(std::vector<int>& adjOuter, std::vector<int>& adj) const;
  void freeNodes(const std::vector<int>& adjOuter, std::vector<int>& compact, std::vector<int>& nodeOf) const;
  std::vector<int> orderFreeNodes(const std::vector<int>& adjOuter, const std::vector<int>& adj,
                                  const std::vector<int>& compact, const std::vector<int>& nodeOf);
  std::vector<int> numberFreeDofs(const std::vector<int>& order, const std::vector<int>& nodeOf);
  void stiffnessPattern(const std::vector<int>& order, const std::vector<int>& nodeOf, const std::vector<int>& adjOuter,
                        const std::vector<int>& adj, const std::vector<int>& rank);
  void orderTets(const std::vector<int>& rank);

  // --- the assembly (assembly.cpp) ---
  // assemble tangent (free-free lower; tangent = false: K is left as it is) and internal forces (all
  // dofs) at displacement u
  void assemble(const Eigen::VectorXd& u, bool nonlinear, Eigen::VectorXd& fint, bool tangent = true);
  template <int NEN>
  void assembleT(const Eigen::VectorXd& u, bool nonlinear, Eigen::VectorXd& fint, bool tangent);
  template <int NEN>
  void assembleTet(int t, const Eigen::VectorXd& u, bool nonlinear, double* val, double* fi) const;
  Eigen::VectorXd freePart(const Eigen::VectorXd& full) const;

  // --- the factorisation of K and its solves (sparse_cholesky.cpp) ---
  void factorize(double& seconds);
  Eigen::VectorXd solveFree(const Eigen::VectorXd& rhs);

  // --- the results (solver.cpp) ---
  void stresses(const Eigen::VectorXd& u, bool nonlinear, Result& res) const;
  template <int NEN>
  void stressesT(const Eigen::VectorXd& u, bool nonlinear, Result& res) const;
  std::string invertedAt(const Eigen::VectorXd& u) const;

  // --- the Newton path (newton.cpp) ---
  struct NewtonPath;
  Result path(const NewtonOptions& opt, double scale, const Eigen::VectorXd* ctrl, double dTarget, double& factorSeconds);
};

}  // namespace pectus::fe
