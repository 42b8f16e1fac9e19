// The CHOLMOD wrapper (sparse_cholesky.h) and the solver's factorisation of K with its checks.
#include "sparse_cholesky.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "blas_threads.h"
#include "memory_budget.h"
#include "pectus/errors.h"
#include "solver_impl.h"

namespace pectus::fe {

std::vector<int> Cholmod::orderNodes(std::vector<int>& outer, std::vector<int>& inner, int method) {
  cholmod_common& c = cholmod();
  const int nn = static_cast<int>(outer.size()) - 1;
  cholmod_sparse G{};
  G.nrow = G.ncol = static_cast<size_t>(nn);
  G.nzmax = inner.size();
  G.p = outer.data();
  G.i = inner.data();
  G.stype = -1;  // lower triangle
  G.itype = CHOLMOD_INT;
  G.xtype = CHOLMOD_PATTERN;
  G.dtype = CHOLMOD_DOUBLE;
  G.sorted = 1;
  G.packed = 1;
  const int nmethods = c.nmethods, ordering = c.method[0].ordering, supernodal = c.supernodal;
  c.nmethods = method < 0 ? 0 : 1;
  if (method >= 0) c.method[0].ordering = method;
  c.supernodal = CHOLMOD_SIMPLICIAL;  // the ordering (and its postorder) is all that is kept
  cholmod_factor* L = nn > 0 ? cholmod_analyze(&G, &c) : nullptr;
  c.nmethods = nmethods;
  c.method[0].ordering = ordering;
  c.supernodal = supernodal;
  std::vector<int> order;
  if (L) {
    const int* perm = static_cast<const int*>(L->Perm);
    order.assign(perm, perm + nn);
    nodeOrdering = L->ordering;
    cholmod_free_factor(&L, &c);
  }
  return order;
}

double Cholmod::factorEntries() {
  const cholmod_factor* L = m_cholmodFactor;
  if (!L) return 0;
  return std::max(double(cholmod().lnz), L->is_super ? double(L->xsize) : 0.0);
}

bool Cholmod::analyzeInOrder(const Eigen::SparseMatrix<double>& K) {
  cholmod_common& c = cholmod();
  if (m_cholmodFactor) cholmod_free_factor(&m_cholmodFactor, &c);
  const int nmethods = c.nmethods, ordering = c.method[0].ordering, postorder = c.postorder;
  c.nmethods = 1;
  c.method[0].ordering = CHOLMOD_NATURAL;
  c.postorder = 0;
  cholmod_sparse A = Eigen::viewAsCholmod(K.selfadjointView<Eigen::Lower>());
  m_cholmodFactor = cholmod_analyze(&A, &c);
  c.nmethods = nmethods;
  c.method[0].ordering = ordering;
  c.postorder = postorder;
  if (!m_cholmodFactor) return false;
  m_isInitialized = true;
  m_info = Eigen::Success;
  m_analysisIsOk = true;
  m_factorizationIsOk = false;
  return true;
}

void Solver::Impl::factorize(double& seconds) {
  auto t0 = std::chrono::steady_clock::now();
  double analyseSeconds = 0;
  if (!analysed) {
    if (!orderByNodes || !chol.analyzeInOrder(K)) chol.analyzePattern(K);
    requireFactorFits(chol.factorEntries(), nFree);
    analysed = true;
    analyseSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  setBlasThreads(chol.cholmod().fl);
  chol.factorize(K);
  seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (std::getenv("PECTUS_FE_VERBOSE"))
    std::fprintf(stderr, "[pectus_fe] n=%d nnz(A)=%ld nnz(L)=%.0f flops=%.3g ordering=%d%s (%.3f s) analyse %.3f s factor %.3f s\n",
                 nFree, static_cast<long>(K.nonZeros()), chol.cholmod().lnz, chol.cholmod().fl,
                 orderByNodes                      ? chol.nodeOrdering
                 : chol.cholmod().selected >= 0 ? chol.cholmod().method[chol.cholmod().selected].ordering
                                                : -1,
                 orderByNodes ? " on the nodes" : "", orderSeconds, analyseSeconds, seconds);
  if (chol.info() != Eigen::Success) {
    std::ostringstream s;
    s << "The stiffness matrix is singular or not positive definite: the model is not held enough (fix more "
         "nodes so that every part of the mesh is connected to a fixed node), or an element is inverted.";
    const int col = chol.failedColumn();
    const auto dof = std::find(freeIndex.begin(), freeIndex.end(), col);
    if (col >= 0 && dof != freeIndex.end()) {
      const int node = int(dof - freeIndex.begin()) / 3;
      const Eigen::Vector3d& x = m->nodes[std::size_t(node)];
      s << " The factorisation stopped at node " << node << " (" << x.x() << ", " << x.y() << ", " << x.z() << ").";
    }
    throw SolverFailure(s.str());
  }
  const double rc = chol.rcond();
  if (!(rc > 1e-15)) {
    std::ostringstream s;
    s << "The stiffness matrix is numerically singular (reciprocal condition estimate " << rc
      << "): the fixed nodes do not prevent a rigid-body motion of some part of the model; fix more nodes "
         "(at least three non-collinear nodes per connected part).";
    throw SolverFailure(s.str());
  }
}

Eigen::VectorXd Solver::Impl::solveFree(const Eigen::VectorXd& rhs) {
  Eigen::VectorXd x = chol.solve(rhs);
  if (!x.allFinite())
    throw SolverFailure("The linear solve produced non-finite displacements (singular stiffness matrix): fix more nodes.");
  return x;
}

}  // namespace pectus::fe
