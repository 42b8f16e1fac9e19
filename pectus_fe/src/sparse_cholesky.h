// CHOLMOD's supernodal Cholesky factorisation, as Eigen wraps it, with what the solver adds: the ordering
// of the nodes' graph, the symbolic analysis of a matrix already in that order, the factor's size and the
// reciprocal condition estimate.
#pragma once
#include <vector>

#include <Eigen/CholmodSupport>
#include <Eigen/Sparse>

namespace pectus::fe {

class Cholmod : public Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> {
 public:
  double rcond() { return m_cholmodFactor ? cholmod_rcond(m_cholmodFactor, &cholmod()) : 0.0; }
  // after a failed factorisation: the column (in K's numbering) whose pivot was not positive, or -1
  int failedColumn() const {
    const cholmod_factor* L = m_cholmodFactor;
    if (!L || L->minor >= L->n) return -1;
    return L->Perm ? static_cast<const int*>(L->Perm)[L->minor] : static_cast<int>(L->minor);
  }

  // Fill-reducing ordering of the graph of the nodes (lower-triangular pattern `outer`/`inner`, compact
  // node numbers) instead of the dofs: the graph is 3x smaller (9x fewer edges), and no separator cuts
  // through a node. CHOLMOD's own default strategy picks the method: AMD, then METIS where AMD's fill is
  // large, keeping the one with fewer flops (the rib cage's thin bones: AMD, 30 % fewer flops than METIS
  // and found in 0.02 s instead of 0.95 s; a solid block: METIS). `method` forces one (CHOLMOD_AMD ...).
  // The order comes back postordered (children before parents). Empty if CHOLMOD failed.
  std::vector<int> orderNodes(std::vector<int>& outer, std::vector<int>& inner, int method = -1);
  int nodeOrdering = -1;  // the method orderNodes used (CHOLMOD_AMD, CHOLMOD_METIS, ...)

  // entries of the numeric factor the analysis prepared (a supernodal factor stores its supernodes' full
  // columns: more than the nonzeros CHOLMOD counts)
  double factorEntries();

  // Symbolic analysis of K (lower triangle) whose dofs are already numbered in the fill-reducing order,
  // postordered (orderNodes): CHOLMOD's natural ordering without its postorder, so that it factorises K
  // as it is stored. With an ordering of its own, CHOLMOD makes two scattered transposes of K per
  // factorisation (and more in the analysis): 0.5 s of the rib cage's 4 s analysis. False if CHOLMOD failed.
  bool analyzeInOrder(const Eigen::SparseMatrix<double>& K);
};

}  // namespace pectus::fe
