// The solver's public face (solver.h): the setup of a problem, the linear solve, the nonlinear and the
// displacement-controlled solves (their path: newton.cpp), the stresses and the report of an inverted tet.
// The units behind it: materials/ (the constitutive laws), element.cpp (the tets' kernels), assembly.cpp,
// setup.cpp, sparse_cholesky.cpp (CHOLMOD), memory_budget.cpp and blas_threads.cpp.
#include "pectus/fe/solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <string>

#include "pectus/errors.h"
#include "solver_impl.h"

namespace pectus::fe {

using Eigen::Matrix3d;
using Eigen::Vector3d;

void Problem::addForce(int node, const Vector3d& f) {
  if (mesh && force.size() != mesh->nodes.size()) force.resize(mesh->nodes.size(), Vector3d::Zero());
  force.at(node) += f;
}

void Solver::Impl::stresses(const Eigen::VectorXd& u, bool nonlinear, Result& res) const {
  if (nen == 10)
    stressesT<10>(u, nonlinear, res);
  else
    stressesT<4>(u, nonlinear, res);
}

// stress and strain at the tet centroid
template <int NEN>
void Solver::Impl::stressesT(const Eigen::VectorXd& u, bool nonlinear, Result& res) const {
  const int nt = m->numTets();
  res.vonMises.assign(nt, 0.0);
  res.eqStrain.assign(nt, 0.0);
#pragma omp parallel for schedule(static) if (nt >= minParallelTets())
  for (int t = 0; t < nt; ++t) tetStress<NEN>(*m, t, ref, *mat[t], *D[t], u, nonlinear, res.vonMises[t], res.eqStrain[t]);
}

// min det F over the tets' quadrature points and centroids at u (nonlinear kinematics): the first tet
// where it is not positive, as a message naming it, its tissue and its place; empty if none
std::string Solver::Impl::invertedAt(const Eigen::VectorXd& u) const {
  if (u.size() != fext.size() || !u.allFinite()) return {};
  const int nt = m->numTets();
  for (int t = 0; t < nt; ++t) {
    const double minJ = tetMinDetF(*m, t, nen, ref, u);
    if (minJ > 0) continue;
    static const char* kNames[] = {"", " (bone)", " (cartilage)", " (sternum)"};
    const int tis = m->tissue[std::size_t(t)];
    const Vector3d c = m->centroid(t), uc = [&] {
      Vector3d s = Vector3d::Zero();
      for (int a = 0; a < 4; ++a) s += u.segment<3>(3 * m->tets[t][a]);
      return Vector3d(s / 4);
    }();
    std::ostringstream o;
    o.precision(4);
    o << "tetrahedron " << t << " of tissue code " << tis << (tis >= 1 && tis <= 3 ? kNames[tis] : "") << " ("
      << materialModelName(mat[t]->model) << ", E " << mat[t]->E << " MPa) at (" << c.x() << ", " << c.y() << ", "
      << c.z() << ") mm, displaced by (" << uc.x() << ", " << uc.y() << ", " << uc.z() << ") mm (det F = " << minJ
      << ")";
    return o.str();
  }
  return {};
}

Solver::Solver(const Problem& prob) : impl_(std::make_unique<Impl>()) {
  Impl& I = *impl_;
  I.p = prob;
  if (!prob.mesh) throw InputError("FE problem without a mesh.");
  const TetMesh& m = *prob.mesh;
  I.m = &m;
  I.nen = m.nodesPerTet();
  I.ref.setOrder(m.order);
  if (m.tets.empty()) throw TopologyError("The FE mesh has no tetrahedra.");
  if (m.tissue.size() != m.tets.size()) throw InputError("The FE mesh needs one tissue label per tetrahedron.");
  I.checkTets();
  I.bindMaterials(prob);
  I.setLoads(prob);
  std::vector<int> adjOuter, adj;
  I.nodeAdjacency(adjOuter, adj);
  std::vector<int> compact, nodeOf;
  I.freeNodes(adjOuter, compact, nodeOf);
  const std::vector<int> order = I.orderFreeNodes(adjOuter, adj, compact, nodeOf);
  const std::vector<int> rank = I.numberFreeDofs(order, nodeOf);
  I.stiffnessPattern(order, nodeOf, adjOuter, adj, rank);
  I.orderTets(rank);
}

Solver::~Solver() = default;

int Solver::numFreeDofs() const { return impl_->nFree; }

Result Solver::solveLinear(double scale) {
  Impl& I = *impl_;
  using Clock = std::chrono::steady_clock;
  const auto since = [](Clock::time_point a) { return std::chrono::duration<double>(Clock::now() - a).count(); };
  auto t = Clock::now();
  Result res;
  res.u = scale * I.prescribed;
  Eigen::VectorXd fint;
  I.assemble(res.u, false, fint);
  Eigen::VectorXd r = I.freePart(scale * I.fext - fint);
  const double tAssemble = since(t);
  I.factorize(lastFactorSeconds_);
  t = Clock::now();
  const Eigen::VectorXd du = I.solveFree(r);
  for (size_t d = 0; d < I.freeIndex.size(); ++d)
    if (I.freeIndex[d] >= 0) res.u(d) += du(I.freeIndex[d]);
  const double tSolve = since(t);
  t = Clock::now();
  // residual check: catches near-singular systems the factorisation let through. The stiffness is linear,
  // so the free part of the internal force at u is the one at the prescribed displacements plus K du.
  const Eigen::VectorXd Kdu = I.K.selfadjointView<Eigen::Lower>() * du;
  const double rn = (r - Kdu).norm();
  const double ref = std::max({r.norm(), Kdu.norm(), 1e-30});
  if (!(rn <= 1e-6 * ref))
    throw SolverFailure("The linear system could not be solved accurately (relative residual " + std::to_string(rn / ref) +
                     "): the model is nearly singular; fix more nodes.");
  const double tResidual = since(t);
  t = Clock::now();
  res.increments = 1;
  res.newtonIterations = 1;
  I.stresses(res.u, false, res);
  if (std::getenv("PECTUS_FE_VERBOSE"))
    std::fprintf(stderr, "[pectus_fe] linear: assemble %.3f s (%zu colours of %d-tet chunks), solve %.3f s, residual check %.3f s, stresses %.3f s\n",
                 tAssemble, I.colors.size(), kChunkTets, tSolve, tResidual, since(t));
  return res;
}

Result Solver::solveNonlinear(const NewtonOptions& opt, double scale) {
  return impl_->path(opt, scale, nullptr, 0, lastFactorSeconds_);
}

Result Solver::solveControlled(const Eigen::VectorXd& weights, double target, const NewtonOptions& opt) {
  Impl& I = *impl_;
  if (weights.size() != I.fext.size())
    throw InputError("Displacement control: need one weight per degree of freedom (3 x the node count).");
  if (!(std::abs(target) > 0) || !std::isfinite(target)) throw InputError("Displacement control: the target must be a non-zero number (mm).");
  for (Eigen::Index d = 0; d < I.prescribed.size(); ++d)
    if (I.prescribed(d) != 0)
      throw InputError("Displacement control needs zero prescribed displacements (they would not follow the load "
                       "factor it finds); prescribe them in a separate step or use load control.");
  const Eigen::VectorXd w = I.freePart(weights);
  if (!(w.norm() > 0)) throw InputError("Displacement control: every weighted degree of freedom is fixed; weight free nodes.");
  return I.path(opt, 1.0, &w, target, lastFactorSeconds_);
}

std::vector<double> averageToNodes(const TetMesh& m, const std::vector<double>& perTet) {
  std::vector<double> sum(m.nodes.size(), 0.0), w(m.nodes.size(), 0.0);
  for (int t = 0; t < m.numTets(); ++t) {
    const double v = std::abs(m.tetVolume(t));
    for (int a = 0; a < m.nodesPerTet(); ++a) {
      sum[m.tets[t][a]] += v * perTet[t];
      w[m.tets[t][a]] += v;
    }
  }
  for (size_t i = 0; i < sum.size(); ++i) sum[i] = w[i] > 0 ? sum[i] / w[i] : 0.0;
  return sum;
}

}  // namespace pectus::fe
