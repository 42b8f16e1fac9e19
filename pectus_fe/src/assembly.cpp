// The global assembly: the pattern of K and the order the tets are visited in, the colouring that makes
// the parallel assembly deterministic, and the sums of the element tangents and forces into K and f.
#include <algorithm>
#include <cstdint>
#include <limits>

#include "solver_impl.h"

namespace pectus::fe {

namespace {

int gMinParallelTets = 2048;  // smaller loops over tets run in one thread (setMinParallelTets, assembleT)

// greedy colouring of the chunks of kChunkTets consecutive tets of `order` (deterministic): each chunk
// takes the lowest colour that no chunk at its nodes has yet, so no two chunks of a colour share a
// node. Corners suffice: tets sharing a TET10 mid-edge node share that edge's corners. The colours at
// a node are bits of a 64-bit mask for the first 64 colours (PECTUS_FE_VERBOSE prints how many), then a list.
std::vector<std::vector<int>> colorChunks(const TetMesh& mesh, const std::vector<int>& order) {
  std::vector<std::vector<int>> out;
  std::vector<std::uint64_t> mask(mesh.nodes.size(), 0);
  std::vector<std::vector<int>> more;  // colours >= 64 at a node (rare)
  const int nt = static_cast<int>(order.size()), chunks = (nt + kChunkTets - 1) / kChunkTets;
  std::vector<int> nodes;
  for (int k = 0; k < chunks; ++k) {
    nodes.clear();
    for (int oi = k * kChunkTets; oi < std::min(nt, (k + 1) * kChunkTets); ++oi)
      for (int a = 0; a < 4; ++a) nodes.push_back(mesh.tets[std::size_t(order[std::size_t(oi)])][a]);
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    std::uint64_t taken = 0;
    for (int v : nodes) taken |= mask[std::size_t(v)];
    std::size_t c = 0;
    if (~taken) {
      while (taken >> c & 1u) ++c;
    } else {
      if (more.empty()) more.resize(mesh.nodes.size());
      for (c = 64;; ++c) {
        bool free = true;
        for (std::size_t i = 0; i < nodes.size() && free; ++i) {
          const auto& l = more[std::size_t(nodes[i])];
          free = std::find(l.begin(), l.end(), static_cast<int>(c)) == l.end();
        }
        if (free) break;
      }
    }
    if (c >= out.size()) out.resize(c + 1);
    out[c].push_back(k);
    for (int v : nodes) {
      if (c < 64) mask[std::size_t(v)] |= std::uint64_t(1) << c;
      else more[std::size_t(v)].push_back(static_cast<int>(c));
    }
  }
  return out;
}

// adds the element matrix Ke (its dofs' free indices fdof, -1: constrained) into the values val of K's
// lower triangle. The element's dofs by free index (constrained ones first): a column's rows are then the
// dofs after it, ascending, found by one forward walk along the column (a binary search per entry
// mispredicts most of its branches)
template <int ND>
void addToLowerTriangle(const Eigen::SparseMatrix<double>& K, const int (&fdof)[ND],
                        const Eigen::Matrix<double, ND, ND>& Ke, double* val) {
  int byIndex[ND];
  for (int r = 0; r < ND; ++r) byIndex[r] = r;
  for (int r = 1; r < ND; ++r)
    for (int q = r; q > 0 && fdof[byIndex[q - 1]] > fdof[byIndex[q]]; --q) std::swap(byIndex[q - 1], byIndex[q]);
  const int* rows = K.innerIndexPtr();
  for (int ci = 0; ci < ND; ++ci) {
    const int c = byIndex[ci];
    if (fdof[c] < 0) continue;
    int k = K.outerIndexPtr()[fdof[c]];
    for (int ri = ci; ri < ND; ++ri) {
      const int r = byIndex[ri];
      while (rows[k] < fdof[r]) ++k;
      val[k] += Ke(r, c);
    }
  }
}

}  // namespace

void setMinParallelTets(int tets) { gMinParallelTets = std::max(1, tets); }
int minParallelTets() { return gMinParallelTets; }

void Solver::Impl::assemble(const Eigen::VectorXd& u, bool nonlinear, Eigen::VectorXd& fint, bool tangent) {
  if (nen == 10)
    assembleT<10>(u, nonlinear, fint, tangent);
  else
    assembleT<4>(u, nonlinear, fint, tangent);
}

template <int NEN>
void Solver::Impl::assembleT(const Eigen::VectorXd& u, bool nonlinear, Eigen::VectorXd& fint, bool tangent) {
  if (tangent) std::fill(K.valuePtr(), K.valuePtr() + K.nonZeros(), 0.0);
  fint.setZero(u.size());
  double* val = K.valuePtr();
  double* fi = fint.data();
  if (colors.empty()) colors = colorChunks(*m, tetOrder);
  // The tets are assembled in chunks of kChunkTets consecutive tets of tetOrder (a compact region of
  // the mesh, so a chunk touches nearby columns of K), one thread per chunk. Chunks of one colour share
  // no node: within a colour every entry of K and fint gets contributions from one chunk only, in that
  // chunk's order, so the sums are formed in the same order whatever the number of threads
  // (byte-identical results with 1 or N threads; atomic adds would sum in thread-timing order).
  // A colour of a few hundred tets is assembled in one thread: a parallel region per colour costs a
  // barrier, and on a machine whose cores are busy with other jobs a barrier waits for a descheduled
  // thread (a 480-tet cantilever, 40 Newton iterations, load ~7: 0.07 s on one thread, 6.7-14 s with
  // two threads and a region per colour). Colouring single tets instead of chunks would make every
  // colour a sweep over all of K (the rib cage's 360k-tet assembly: 0.5-0.8 s against 0.35 s).
  const int nt = m->numTets();
  for (const std::vector<int>& group : colors) {
    const int ng = static_cast<int>(group.size());
#pragma omp parallel for schedule(dynamic, 1) if (ng > 1 && ng * kChunkTets >= gMinParallelTets)
    for (int gi = 0; gi < ng; ++gi)
      for (int oi = group[gi] * kChunkTets; oi < std::min(nt, (group[gi] + 1) * kChunkTets); ++oi)
        assembleTet<NEN>(tetOrder[std::size_t(oi)], u, nonlinear, tangent ? val : nullptr, fi);
  }
}

// one tet's tangent and internal forces, added into K's values (val null: forces only) and fint
template <int NEN>
void Solver::Impl::assembleTet(int t, const Eigen::VectorXd& u, bool nonlinear, double* val, double* fi) const {
  constexpr int ND = 3 * NEN;
  Eigen::Matrix<double, ND, ND> Ke;
  Eigen::Matrix<double, ND, 1> fe;
  tetTangent<NEN>(*m, t, ref, *mat[t], *D[t], u, nonlinear, val != nullptr, Ke, fe);
  int dofs[ND], fdof[ND];
  for (int a = 0; a < NEN; ++a)
    for (int i = 0; i < 3; ++i) dofs[3 * a + i] = 3 * m->tets[t][a] + i, fdof[3 * a + i] = freeIndex[3 * m->tets[t][a] + i];
  for (int r = 0; r < ND; ++r) fi[dofs[r]] += fe(r);
  if (!val) return;
  addToLowerTriangle<ND>(K, fdof, Ke, val);
}

Eigen::VectorXd Solver::Impl::freePart(const Eigen::VectorXd& full) const {
  Eigen::VectorXd r(nFree);
  for (size_t d = 0; d < freeIndex.size(); ++d)
    if (freeIndex[d] >= 0) r(freeIndex[d]) = full(d);
  return r;
}

// node adjacency (compressed rows, sorted, with the node itself); nodes without tets have no row entries
void Solver::Impl::nodeAdjacency(std::vector<int>& adjOuter, std::vector<int>& adj) const {
  const int n = m->numNodes();
  adjOuter.assign(std::size_t(n) + 1, 0);
  for (const auto& e : m->tets)
    for (int a = 0; a < nen; ++a) adjOuter[std::size_t(e[a]) + 1] += nen;
  for (int i = 0; i < n; ++i) adjOuter[std::size_t(i) + 1] += adjOuter[std::size_t(i)];
  adj.resize(std::size_t(adjOuter[std::size_t(n)]));
  std::vector<int> fill(adjOuter.begin(), adjOuter.end() - 1);
  for (const auto& e : m->tets)
    for (int a = 0; a < nen; ++a)
      for (int b = 0; b < nen; ++b) adj[std::size_t(fill[std::size_t(e[a])]++)] = e[b];
  int k = 0;  // sort and deduplicate each row in place
  for (int i = 0; i < n; ++i) {
    const auto first = adj.begin() + adjOuter[std::size_t(i)], last = adj.begin() + adjOuter[std::size_t(i) + 1];
    std::sort(first, last);
    const int start = k;
    for (auto it = first; it != last; ++it)
      if (it == first || *it != *(it - 1)) adj[std::size_t(k++)] = *it;
    adjOuter[std::size_t(i)] = start;
  }
  adjOuter[std::size_t(n)] = k;
  adj.resize(std::size_t(k));
}

// lower-triangular pattern of K (zero values): the column of a free dof holds the free dofs at or after it
// of the node's neighbours; with the neighbours sorted by rank the rows come out sorted
void Solver::Impl::stiffnessPattern(const std::vector<int>& order, const std::vector<int>& nodeOf,
                                    const std::vector<int>& adjOuter, const std::vector<int>& adj,
                                    const std::vector<int>& rank) {
  std::vector<int> outer(std::size_t(nFree) + 1, 0), inner, nbrs;
  inner.reserve(static_cast<size_t>(nFree) * 20);
  int col = 0;
  for (int i : order) {
    const int node = nodeOf[std::size_t(i)];
    nbrs.assign(adj.begin() + adjOuter[std::size_t(node)], adj.begin() + adjOuter[std::size_t(node) + 1]);
    std::sort(nbrs.begin(), nbrs.end(), [&](int x, int y) { return rank[std::size_t(x)] < rank[std::size_t(y)]; });
    for (int d = 0; d < 3; ++d) {
      const int fc = freeIndex[3 * std::size_t(node) + std::size_t(d)];
      if (fc < 0) continue;
      for (int j : nbrs)
        for (int e = 0; e < 3; ++e) {
          const int fr = freeIndex[3 * std::size_t(j) + std::size_t(e)];
          if (fr >= fc) inner.push_back(fr);
        }
      outer[std::size_t(++col)] = static_cast<int>(inner.size());
    }
  }
  std::vector<double> zeros(inner.size(), 0.0);
  K = Eigen::Map<Eigen::SparseMatrix<double>>(nFree, nFree, static_cast<Eigen::Index>(inner.size()), outer.data(),
                                              inner.data(), zeros.data());
}

// the assembly visits the tets by their first node in the dof order (colorChunks)
void Solver::Impl::orderTets(const std::vector<int>& rank) {
  std::vector<int> first(std::size_t(m->numTets()));
  for (int t = 0; t < m->numTets(); ++t) {
    int r = std::numeric_limits<int>::max();
    for (int a = 0; a < 4; ++a) r = std::min(r, rank[std::size_t(m->tets[std::size_t(t)][a])]);
    first[std::size_t(t)] = r;
  }
  tetOrder.resize(first.size());
  for (std::size_t t = 0; t < first.size(); ++t) tetOrder[t] = static_cast<int>(t);
  std::stable_sort(tetOrder.begin(), tetOrder.end(),
                   [&](int x, int y) { return first[std::size_t(x)] < first[std::size_t(y)]; });
}

}  // namespace pectus::fe
