// The problem's setup (Solver's constructor), step by step: the tets checked, the materials bound, the
// loads and fixed dofs, the free nodes, their fill-reducing order and the free dofs numbered in it.
#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <limits>
#include <string>

#include "materials/material.h"
#include "pectus/errors.h"
#include "solver_impl.h"

namespace pectus::fe {

Solver::Impl::Impl() {
  chol.cholmod().print = 0;  // errors are reported by exceptions, not on stderr
  if (const char* o = std::getenv("PECTUS_FE_ORDERING")) {  // experiments: amd | metis | nesdis
    orderByNodes = false;
    chol.cholmod().nmethods = 1;
    const std::string s(o);
    chol.cholmod().method[0].ordering = s == "metis" ? CHOLMOD_METIS : s == "nesdis" ? CHOLMOD_NESDIS : CHOLMOD_AMD;
  }
}

// every tet references existing nodes and has a positive volume; a TET10 whose mid-edge nodes lie far
// from its edges' midpoints can fold inside although its corners do not: its Jacobian must be positive at
// every quadrature point and at the centroid (where the stresses are taken), else its stiffness and
// stresses are meaningless (NaN stresses)
void Solver::Impl::checkTets() const {
  const int n = m->numNodes();
  for (int t = 0; t < m->numTets(); ++t) {
    for (int a = 0; a < nen; ++a)
      if (m->tets[t][a] < 0 || m->tets[t][a] >= n) throw TopologyError("Tetrahedron " + std::to_string(t) + " has an invalid node index.");
    if (!(m->tetVolume(t) > 0))
      throw TopologyError("Tetrahedron " + std::to_string(t) + " is inverted or flat (volume <= 0).");
    if (nen == 10) {
      Eigen::Matrix<double, 10, 3> G;
      bool ok = gradients<10>(*m, t, ref.centroidDN, 1.0, G) > 0;
      for (std::size_t q = 0; q < ref.quad.size() && ok; ++q) ok = gradients<10>(*m, t, ref.quadDN[q], 1.0, G) > 0;
      if (!ok)
        throw TopologyError("Tetrahedron " + std::to_string(t) +
                         " (quadratic) folds inside: its mid-edge nodes are too far from its edges' midpoints (the "
                         "Jacobian is not positive everywhere in it). Use straight-sided quadratic tets or refine there.");
    }
  }
}

// the elasticity matrix of each tissue's material, and per tet its material (in our copy p) and matrix
void Solver::Impl::bindMaterials(const Problem& prob) {
  for (const auto& kv : prob.materials) {
    if (!(kv.second.E > 0) || !(kv.second.nu > -1 && kv.second.nu < 0.5))
      throw InputError("Material of tissue " + std::to_string(kv.first) + ": need E > 0 and -1 < Poisson ratio < 0.5.");
    Dby[kv.first] = linearElasticity(kv.second);
  }
  D.resize(m->numTets());
  mat.resize(m->numTets());
  for (int t = 0; t < m->numTets(); ++t) {
    auto it = prob.materials.find(m->tissue[t]);
    if (it == prob.materials.end())
      throw InputError("No material for tissue label " + std::to_string(m->tissue[t]) + " (tetrahedron " + std::to_string(t) + ").");
    mat[t] = &it->second;
    D[t] = &Dby[m->tissue[t]];
  }
  // rebind material pointers to our copy
  for (int t = 0; t < m->numTets(); ++t) mat[t] = &p.materials.at(m->tissue[t]);
}

// the fixed dofs with their prescribed displacements, and the nodal forces
void Solver::Impl::setLoads(const Problem& prob) {
  const int n = m->numNodes();
  if (prob.fixed.empty())
    throw InputError("No fixed nodes: the stiffness matrix is singular (the model can move as a rigid body). "
                     "Fix at least the nodes where the model is held (e.g. the costovertebral joints).");
  isConstrained.assign(3 * n, 0);
  prescribed.setZero(3 * n);
  for (const auto& d : prob.fixed) {
    if (d.node < 0 || d.node >= n || d.dof < 0 || d.dof > 2) throw InputError("Fixed node/dof out of range.");
    isConstrained[3 * d.node + d.dof] = 1;
    prescribed(3 * d.node + d.dof) = d.value;
  }
  fext.setZero(3 * n);
  if (!prob.force.empty()) {
    if (static_cast<int>(prob.force.size()) != n) throw InputError("Force vector size differs from the node count.");
    for (int i = 0; i < n; ++i) fext.segment<3>(3 * i) = prob.force[i];
  }
}

// the nodes with a free dof, compactly numbered (the ordering's graph): compact per node (-1: none),
// nodeOf per compact number
void Solver::Impl::freeNodes(const std::vector<int>& adjOuter, std::vector<int>& compact,
                             std::vector<int>& nodeOf) const {
  const int n = m->numNodes();
  compact.assign(std::size_t(n), -1);
  for (int i = 0; i < n; ++i) {
    if (adjOuter[std::size_t(i)] == adjOuter[std::size_t(i) + 1]) continue;  // used by no tet: no dofs
    for (int d = 0; d < 3 && compact[std::size_t(i)] < 0; ++d)
      if (!isConstrained[3 * std::size_t(i) + std::size_t(d)]) {
        compact[std::size_t(i)] = static_cast<int>(nodeOf.size());
        nodeOf.push_back(i);
      }
  }
  if (nodeOf.empty()) throw InputError("Every degree of freedom is fixed: nothing to solve.");
}

// fill-reducing order of those nodes (see Cholmod::orderNodes), as compact numbers; their free dofs are
// numbered in it, node by node, so CHOLMOD factorises K as it is (PECTUS_FE_ORDERING: node order, CHOLMOD
// orders the dofs)
std::vector<int> Solver::Impl::orderFreeNodes(const std::vector<int>& adjOuter, const std::vector<int>& adj,
                                              const std::vector<int>& compact, const std::vector<int>& nodeOf) {
  std::vector<int> order;
  if (orderByNodes) {
    std::vector<int> gOuter(1, 0), gInner;
    gInner.reserve(adj.size() / 2 + nodeOf.size());
    for (int i : nodeOf) {
      for (int k = adjOuter[std::size_t(i)]; k < adjOuter[std::size_t(i) + 1]; ++k) {
        const int j = compact[std::size_t(adj[std::size_t(k)])];
        if (j >= compact[std::size_t(i)]) gInner.push_back(j);
      }
      std::sort(gInner.begin() + gOuter.back(), gInner.end());
      gOuter.push_back(static_cast<int>(gInner.size()));
    }
    const auto t0 = std::chrono::steady_clock::now();
    order = chol.orderNodes(gOuter, gInner);
    orderSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (order.empty()) orderByNodes = false;  // CHOLMOD failed: it orders the dofs itself
  }
  if (order.empty())
    for (std::size_t k = 0; k < nodeOf.size(); ++k) order.push_back(static_cast<int>(k));
  return order;
}

// numbers the free dofs (freeIndex, nFree) node by node in that order; returns each node's position in it
std::vector<int> Solver::Impl::numberFreeDofs(const std::vector<int>& order, const std::vector<int>& nodeOf) {
  const int n = m->numNodes();
  std::vector<int> rank(std::size_t(n), std::numeric_limits<int>::max());
  freeIndex.assign(3 * std::size_t(n), -1);
  for (std::size_t k = 0; k < order.size(); ++k) {
    const int i = nodeOf[std::size_t(order[k])];
    rank[std::size_t(i)] = static_cast<int>(k);
    for (int d = 0; d < 3; ++d)
      if (!isConstrained[3 * std::size_t(i) + std::size_t(d)]) freeIndex[3 * std::size_t(i) + std::size_t(d)] = nFree++;
  }
  return rank;
}

}  // namespace pectus::fe
