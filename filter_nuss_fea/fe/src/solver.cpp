#include "pectus/fe/solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include <dlfcn.h>
#include <omp.h>

#include <Eigen/CholmodSupport>
#include <Eigen/Dense>
#include <Eigen/Sparse>

#include "pectus/errors.h"

namespace pectus::fe {

using Eigen::Matrix3d;
using Eigen::Vector3d;

namespace {
int gMinParallelTets = 2048;  // smaller loops over tets run in one thread (setMinParallelTets, assembleT)
}  // namespace

void setMinParallelTets(int tets) { gMinParallelTets = std::max(1, tets); }
int minParallelTets() { return gMinParallelTets; }

std::map<int, Material> thesisMaterials(double nuBone, double nuCartilage) {
  return {{1, {11500.0, nuBone}}, {2, {12.25, nuCartilage}}, {3, {11500.0, nuBone}}};
}

void Problem::addForce(int node, const Vector3d& f) {
  if (mesh && force.size() != mesh->nodes.size()) force.resize(mesh->nodes.size(), Vector3d::Zero());
  force.at(node) += f;
}

namespace {

// Quadrature and shape functions ---------------------------------------------------------------
struct Gauss { double L[4]; double w; };
const std::vector<Gauss>& rule(int order) {
  static const std::vector<Gauss> r1{{{0.25, 0.25, 0.25, 0.25}, 1.0 / 6.0}};
  static const double a = 0.5854101966249685, b = 0.1381966011250105;
  static const std::vector<Gauss> r2{{{a, b, b, b}, 1.0 / 24}, {{b, a, b, b}, 1.0 / 24},
                                     {{b, b, a, b}, 1.0 / 24}, {{b, b, b, a}, 1.0 / 24}};
  return order == 2 ? r2 : r1;
}

// derivatives of the shape functions w.r.t. (xi, eta, zeta) at volume coordinates L (L0 = 1-xi-eta-zeta)
void shapeDerivs(int order, const double L[4], Eigen::Matrix<double, 10, 3>& dN) {
  Eigen::Matrix<double, 10, 4> dL = Eigen::Matrix<double, 10, 4>::Zero();  // dN/dL_k
  if (order == 1) {
    for (int i = 0; i < 4; ++i) dL(i, i) = 1.0;
  } else {
    for (int i = 0; i < 4; ++i) dL(i, i) = 4.0 * L[i] - 1.0;
    for (int k = 0; k < 6; ++k) {
      int a = kTetEdges[k][0], b = kTetEdges[k][1];
      dL(4 + k, a) = 4.0 * L[b];
      dL(4 + k, b) = 4.0 * L[a];
    }
  }
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 3; ++j) dN(i, j) = dL(i, j + 1) - dL(i, 0);
}

inline Eigen::Matrix<double, 6, 6> elasticity(const Material& m) {
  const double lam = m.E * m.nu / ((1 + m.nu) * (1 - 2 * m.nu)), mu = m.E / (2 * (1 + m.nu));
  Eigen::Matrix<double, 6, 6> D = Eigen::Matrix<double, 6, 6>::Zero();
  D.topLeftCorner<3, 3>().setConstant(lam);
  for (int i = 0; i < 3; ++i) D(i, i) += 2 * mu, D(3 + i, 3 + i) = mu;
  return D;
}

inline Eigen::Matrix<double, 6, 1> voigt(const Matrix3d& s, bool engineeringShear) {
  const double f = engineeringShear ? 2.0 : 1.0;
  Eigen::Matrix<double, 6, 1> v;
  v << s(0, 0), s(1, 1), s(2, 2), f * s(0, 1), f * s(1, 2), f * s(0, 2);
  return v;
}

double vonMisesOf(const Matrix3d& s) {
  return std::sqrt(0.5 * ((s(0, 0) - s(1, 1)) * (s(0, 0) - s(1, 1)) + (s(1, 1) - s(2, 2)) * (s(1, 1) - s(2, 2)) +
                          (s(2, 2) - s(0, 0)) * (s(2, 2) - s(0, 0))) +
                   3.0 * (s(0, 1) * s(0, 1) + s(1, 2) * s(1, 2) + s(0, 2) * s(0, 2)));
}
// ANSYS EPEL,EQV: 1/(1+nu') sqrt(1/2 sum (ei-ej)^2 + 3/4 sum gamma^2), gamma engineering shear = 2 e_ij
double eqStrainOf(const Matrix3d& e, double nu) {
  const double g01 = 2 * e(0, 1), g12 = 2 * e(1, 2), g02 = 2 * e(0, 2);
  return std::sqrt(0.5 * ((e(0, 0) - e(1, 1)) * (e(0, 0) - e(1, 1)) + (e(1, 1) - e(2, 2)) * (e(1, 1) - e(2, 2)) +
                          (e(2, 2) - e(0, 0)) * (e(2, 2) - e(0, 0))) +
                   0.75 * (g01 * g01 + g12 * g12 + g02 * g02)) /
         (1.0 + nu);
}

// CHOLMOD's supernodal factorisation calls the BLAS for its dense blocks. Debian's OpenBLAS (pthreads
// build) starts its own busy-waiting threads for every call; beside this program's OpenMP threads, or on a
// machine whose cores are taken by other jobs, they oversubscribe the cores and a factorisation of the rib
// cage's systems (small supernodes, ~1e8-1e9 flops) became 5-10x slower than on one BLAS thread (measured:
// 2.94 s against 0.27 s for a 127k-dof cage). So the BLAS gets one thread for small factorisations and
// OpenMP's thread count from kBlasThreadFlops on (the long cantilever benchmark: 2e11 flops). The call is
// looked up at run time (the BLAS behind libblas.so.3 is chosen by Debian's alternatives; the reference
// BLAS has no threads to set). PECTUS_BLAS_THREADS=n forces n.
constexpr double kBlasThreadFlops = 2e10;
void setBlasThreads(double flops) {
  using SetThreads = void (*)(int);
  static const SetThreads set = [] {
    for (const char* lib : {"libopenblas.so.0", "libblas.so.3", "libopenblas.so"})
      if (void* h = dlopen(lib, RTLD_LAZY | RTLD_NOLOAD))
        if (void* f = dlsym(h, "openblas_set_num_threads")) return reinterpret_cast<SetThreads>(f);
    return reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
  }();
  if (!set) return;
  int n = flops >= kBlasThreadFlops ? omp_get_max_threads() : 1;
  if (const char* e = std::getenv("PECTUS_BLAS_THREADS")) n = std::max(1, std::atoi(e));
  set(n);
}

class Cholmod : public Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> {
 public:
  double rcond() { return m_cholmodFactor ? cholmod_rcond(m_cholmodFactor, &cholmod()) : 0.0; }

  // Symbolic analysis of K (lower triangle) with a fill-reducing ordering that METIS finds on the graph of
  // the nodes instead of the dofs: `nodeOuter`/`nodeInner` is the lower-triangular pattern of the nodes
  // that have free dofs, the free dofs of node k are firstDof[k] .. firstDof[k + 1] - 1. The graph is 3x
  // smaller (9x fewer edges) than K's, so it is ordered faster, and no separator cuts through a node.
  // CHOLMOD then postorders the given ordering and finds the supernodes as usual. False if METIS failed
  // (the caller falls back to CHOLMOD's own choice).
  bool analyzeByNodes(const Eigen::SparseMatrix<double>& K, std::vector<int>& nodeOuter, std::vector<int>& nodeInner,
                      const std::vector<int>& firstDof) {
    cholmod_common& c = cholmod();
    const int nn = static_cast<int>(nodeOuter.size()) - 1;
    cholmod_sparse G{};
    G.nrow = G.ncol = static_cast<size_t>(nn);
    G.nzmax = nodeInner.size();
    G.p = nodeOuter.data();
    G.i = nodeInner.data();
    G.stype = -1;  // lower triangle
    G.itype = CHOLMOD_INT;
    G.xtype = CHOLMOD_PATTERN;
    G.dtype = CHOLMOD_DOUBLE;
    G.sorted = 1;
    G.packed = 1;
    std::vector<int> nodePerm(static_cast<size_t>(nn));
    if (nn == 0 || !cholmod_metis(&G, nullptr, 0, 1, nodePerm.data(), &c)) return false;
    std::vector<int> perm;
    perm.reserve(static_cast<size_t>(K.rows()));
    for (int k : nodePerm)
      for (int d = firstDof[std::size_t(k)]; d < firstDof[std::size_t(k) + 1]; ++d) perm.push_back(d);
    if (static_cast<Eigen::Index>(perm.size()) != K.rows()) return false;
    if (m_cholmodFactor) cholmod_free_factor(&m_cholmodFactor, &c);
    const int nmethods = c.nmethods, ordering = c.method[0].ordering;
    c.nmethods = 1;
    c.method[0].ordering = CHOLMOD_GIVEN;
    cholmod_sparse A = Eigen::viewAsCholmod(K.selfadjointView<Eigen::Lower>());
    m_cholmodFactor = cholmod_analyze_p(&A, perm.data(), nullptr, 0, &c);
    c.nmethods = nmethods;
    c.method[0].ordering = ordering;
    if (!m_cholmodFactor) return false;
    m_isInitialized = true;
    m_info = Eigen::Success;
    m_analysisIsOk = true;
    m_factorizationIsOk = false;
    return true;
  }
};

}  // namespace

struct Solver::Impl {
  Problem p;
  const TetMesh* m = nullptr;
  int nen = 4;
  std::vector<int> freeIndex;                 // per dof: free index or -1
  std::vector<const Material*> mat;           // per tet
  std::vector<Eigen::Matrix<double, 6, 6>> D; // per tet (pointer-free copy by tissue would be smaller)
  std::map<int, Eigen::Matrix<double, 6, 6>> Dby;
  Eigen::VectorXd fext;                        // full, 3n
  Eigen::VectorXd prescribed;                  // full, 3n (0 for free dofs)
  std::vector<char> isConstrained;
  Eigen::SparseMatrix<double> K;               // free x free, lower triangle
  Cholmod chol;
  bool analysed = false;
  std::vector<std::vector<int>> colors;        // tets by colour (colorTets), for the assembly
  // graph of the nodes with free dofs (lower triangle, compact node numbers) and their first free dof:
  // the input of the ordering (Cholmod::analyzeByNodes), dropped after the analysis
  std::vector<int> nodeOuter, nodeInner, nodeFirstDof;
  bool orderByNodes = true;                    // PECTUS_FE_ORDERING=amd|metis|nesdis: CHOLMOD orders the dofs

  int nFree = 0;
  Impl() {
    chol.cholmod().print = 0;  // errors are reported by exceptions, not on stderr
    if (const char* o = std::getenv("PECTUS_FE_ORDERING")) {  // experiments: amd | metis | nesdis
      orderByNodes = false;
      chol.cholmod().nmethods = 1;
      const std::string s(o);
      chol.cholmod().method[0].ordering = s == "metis" ? CHOLMOD_METIS : s == "nesdis" ? CHOLMOD_NESDIS : CHOLMOD_AMD;
    }
  }

  // position of K(row, col) (row >= col) in K.valuePtr()
  int pos(int row, int col) const {
    const int* b = K.innerIndexPtr() + K.outerIndexPtr()[col];
    const int* e = K.innerIndexPtr() + K.outerIndexPtr()[col + 1];
    const int* it = std::lower_bound(b, e, row);
    return static_cast<int>(it - K.innerIndexPtr());
  }

  // element gradients dN/dX at quadrature point, returns det(J)*w
  double gradients(int t, const Gauss& g, Eigen::Matrix<double, 10, 3>& G) const {
    Eigen::Matrix<double, 10, 3> dN;
    shapeDerivs(m->order, g.L, dN);
    Matrix3d J = Matrix3d::Zero();
    for (int a = 0; a < nen; ++a) J += m->nodes[m->tets[t][a]] * dN.row(a);
    const double det = J.determinant();
    const Matrix3d Jinv = J.inverse();
    G.topRows(nen) = dN.topRows(nen) * Jinv;
    return det * g.w;
  }

  // assemble tangent (free-free lower) and internal forces (all dofs) at displacement u
  void assemble(const Eigen::VectorXd& u, bool nonlinear, Eigen::VectorXd& fint) {
    if (nen == 10)
      assembleT<10>(u, nonlinear, fint);
    else
      assembleT<4>(u, nonlinear, fint);
  }

  template <int NEN>
  void assembleT(const Eigen::VectorXd& u, bool nonlinear, Eigen::VectorXd& fint) {
    constexpr int ND = 3 * NEN;
    std::fill(K.valuePtr(), K.valuePtr() + K.nonZeros(), 0.0);
    fint.setZero(u.size());
    double* val = K.valuePtr();
    double* fi = fint.data();
    if (colors.empty()) colors = colorTets(*m);
    // Tets of one colour share no node: within a colour every entry of K and fint gets at most one
    // contribution, so the sums are formed in colour order whatever the number of threads (byte-identical
    // results with 1 or N threads; atomic adds would sum in thread-timing order).
    // A colour of a few hundred tets is assembled in one thread: a parallel region per colour costs a
    // barrier, and on a machine whose cores are busy with other jobs a barrier waits for a descheduled
    // thread (measured, 480-tet cantilever, 40 Newton iterations, load ~7: 0.07 s on one thread, 6.7-14 s
    // with two threads and a region per colour).
    for (const std::vector<int>& group : colors) {
      const int ng = static_cast<int>(group.size());
  #pragma omp parallel for schedule(dynamic, 64) if (ng >= gMinParallelTets)
      for (int gi = 0; gi < ng; ++gi) {
        const int t = group[gi];
        Eigen::Matrix<double, ND, ND> Ke = Eigen::Matrix<double, ND, ND>::Zero();
        Eigen::Matrix<double, ND, 1> fe = Eigen::Matrix<double, ND, 1>::Zero();
        Eigen::Matrix<double, 10, 3> G10;
        Eigen::Matrix<double, NEN, 3> ue;
        for (int a = 0; a < NEN; ++a) ue.row(a) = u.template segment<3>(3 * m->tets[t][a]).transpose();
        const auto& Dm = D[t];
        for (const Gauss& g : rule(m->order)) {
          const double w = gradients(t, g, G10);
          const Eigen::Matrix<double, NEN, 3> G = G10.template topRows<NEN>();
          const Matrix3d H = ue.transpose() * G;  // du_i/dX_j
          Matrix3d F = Matrix3d::Identity();
          Matrix3d E;
          if (nonlinear) {
            F += H;
            E = 0.5 * (H + H.transpose() + H.transpose() * H);
          } else {
            E = 0.5 * (H + H.transpose());
          }
          const Eigen::Matrix<double, 6, 1> Sv = Dm * voigt(E, true);
          Matrix3d S;
          S << Sv(0), Sv(3), Sv(5), Sv(3), Sv(1), Sv(4), Sv(5), Sv(4), Sv(2);
          const Matrix3d P = F * S;  // first Piola (linear: sigma)
          Eigen::Matrix<double, 6, ND> B;
          for (int a = 0; a < NEN; ++a) {
            const Vector3d Ga = G.row(a).transpose();
            fe.template segment<3>(3 * a) += w * P * Ga;
            for (int i = 0; i < 3; ++i) {
              B(0, 3 * a + i) = F(i, 0) * Ga(0);
              B(1, 3 * a + i) = F(i, 1) * Ga(1);
              B(2, 3 * a + i) = F(i, 2) * Ga(2);
              B(3, 3 * a + i) = F(i, 0) * Ga(1) + F(i, 1) * Ga(0);
              B(4, 3 * a + i) = F(i, 1) * Ga(2) + F(i, 2) * Ga(1);
              B(5, 3 * a + i) = F(i, 0) * Ga(2) + F(i, 2) * Ga(0);
            }
          }
          const Eigen::Matrix<double, 6, ND> DB = (w * Dm) * B;
          Ke.noalias() += B.transpose() * DB;
          if (nonlinear) {
            const Eigen::Matrix<double, NEN, NEN> GSG = w * G * S * G.transpose();
            for (int a = 0; a < NEN; ++a)
              for (int b = 0; b < NEN; ++b)
                for (int i = 0; i < 3; ++i) Ke(3 * a + i, 3 * b + i) += GSG(a, b);
          }
        }
        int dofs[ND], fdof[ND];
        for (int a = 0; a < NEN; ++a)
          for (int i = 0; i < 3; ++i) dofs[3 * a + i] = 3 * m->tets[t][a] + i, fdof[3 * a + i] = freeIndex[3 * m->tets[t][a] + i];
        for (int r = 0; r < ND; ++r) fi[dofs[r]] += fe(r);
        for (int c = 0; c < ND; ++c) {
          const int fc = fdof[c];
          if (fc < 0) continue;
          const int* b = K.innerIndexPtr() + K.outerIndexPtr()[fc];
          const int* e = K.innerIndexPtr() + K.outerIndexPtr()[fc + 1];
          for (int r = 0; r < ND; ++r) {
            const int fr = fdof[r];
            if (fr < fc) continue;  // lower triangle only (and skips constrained: -1)
            const int k = static_cast<int>(std::lower_bound(b, e, fr) - K.innerIndexPtr());
            val[k] += Ke(r, c);
          }
        }
      }
    }
  }

  // greedy colouring of the tets (in tet order, deterministic): no two tets of a colour share a node.
  // Corners suffice: tets sharing a TET10 mid-edge node share that edge's corners.
  static std::vector<std::vector<int>> colorTets(const TetMesh& mesh) {
    std::vector<std::vector<int>> out;
    std::vector<std::vector<char>> used;  // used[c][node]: colour c has a tet at the node
    const int nen = 4;
    for (int t = 0; t < mesh.numTets(); ++t) {
      std::size_t c = 0;
      for (; c < out.size(); ++c) {
        bool free = true;
        for (int a = 0; a < nen && free; ++a) free = !used[c][std::size_t(mesh.tets[t][a])];
        if (free) break;
      }
      if (c == out.size()) {
        out.emplace_back();
        used.emplace_back(mesh.nodes.size(), 0);
      }
      out[c].push_back(t);
      for (int a = 0; a < nen; ++a) used[c][std::size_t(mesh.tets[t][a])] = 1;
    }
    return out;
  }

  Eigen::VectorXd freePart(const Eigen::VectorXd& full) const {
    Eigen::VectorXd r(nFree);
    for (size_t d = 0; d < freeIndex.size(); ++d)
      if (freeIndex[d] >= 0) r(freeIndex[d]) = full(d);
    return r;
  }

  void factorize(double& seconds) {
    auto t0 = std::chrono::steady_clock::now();
    double analyseSeconds = 0;
    if (!analysed) {
      if (!orderByNodes || !chol.analyzeByNodes(K, nodeOuter, nodeInner, nodeFirstDof)) chol.analyzePattern(K);
      std::vector<int>().swap(nodeOuter);
      std::vector<int>().swap(nodeInner);
      std::vector<int>().swap(nodeFirstDof);
      analysed = true;
      analyseSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    }
    setBlasThreads(chol.cholmod().fl);
    chol.factorize(K);
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (std::getenv("PECTUS_FE_VERBOSE"))
      std::fprintf(stderr, "[pectus_fe] n=%d nnz(A)=%ld nnz(L)=%.0f flops=%.3g ordering=%d analyse %.3f s factor %.3f s\n",
                   nFree, static_cast<long>(K.nonZeros()), chol.cholmod().lnz, chol.cholmod().fl,
                   chol.cholmod().selected >= 0 ? chol.cholmod().method[chol.cholmod().selected].ordering : -1,
                   analyseSeconds, seconds);
    if (chol.info() != Eigen::Success)
      throw InputError(
          "The stiffness matrix is singular or not positive definite: the model is not held enough (fix more "
          "nodes so that every part of the mesh is connected to a fixed node), or an element is inverted.");
    const double rc = chol.rcond();
    if (!(rc > 1e-15)) {
      std::ostringstream s;
      s << "The stiffness matrix is numerically singular (reciprocal condition estimate " << rc
        << "): the fixed nodes do not prevent a rigid-body motion of some part of the model; fix more nodes "
           "(at least three non-collinear nodes per connected part).";
      throw InputError(s.str());
    }
  }

  Eigen::VectorXd solveFree(const Eigen::VectorXd& rhs) {
    Eigen::VectorXd x = chol.solve(rhs);
    if (!x.allFinite())
      throw InputError("The linear solve produced non-finite displacements (singular stiffness matrix): fix more nodes.");
    return x;
  }

  void stresses(const Eigen::VectorXd& u, bool nonlinear, Result& res) const {
    const int nt = m->numTets();
    res.vonMises.assign(nt, 0.0);
    res.eqStrain.assign(nt, 0.0);
    const Gauss c{{0.25, 0.25, 0.25, 0.25}, 1.0};
#pragma omp parallel for schedule(static) if (nt >= gMinParallelTets)
    for (int t = 0; t < nt; ++t) {
      Eigen::Matrix<double, 10, 3> G, ue;
      for (int a = 0; a < nen; ++a) ue.row(a) = u.segment<3>(3 * m->tets[t][a]).transpose();
      gradients(t, c, G);
      const Matrix3d H = ue.topRows(nen).transpose() * G.topRows(nen);
      Matrix3d E = nonlinear ? Matrix3d(0.5 * (H + H.transpose() + H.transpose() * H)) : Matrix3d(0.5 * (H + H.transpose()));
      const Eigen::Matrix<double, 6, 1> Sv = D[t] * voigt(E, true);
      Matrix3d S;
      S << Sv(0), Sv(3), Sv(5), Sv(3), Sv(1), Sv(4), Sv(5), Sv(4), Sv(2);
      if (nonlinear) {
        const Matrix3d F = Matrix3d::Identity() + H;
        S = F * S * F.transpose() / F.determinant();
      }
      res.vonMises[t] = vonMisesOf(S);
      res.eqStrain[t] = eqStrainOf(E, mat[t]->nu);
    }
  }
};

Solver::Solver(const Problem& prob) : impl_(std::make_unique<Impl>()) {
  Impl& I = *impl_;
  I.p = prob;
  if (!prob.mesh) throw InputError("FE problem without a mesh.");
  const TetMesh& m = *prob.mesh;
  I.m = &m;
  I.nen = m.nodesPerTet();
  if (m.tets.empty()) throw InputError("The FE mesh has no tetrahedra.");
  if (m.tissue.size() != m.tets.size()) throw InputError("The FE mesh needs one tissue label per tetrahedron.");
  const int n = m.numNodes();
  for (int t = 0; t < m.numTets(); ++t) {
    for (int a = 0; a < I.nen; ++a)
      if (m.tets[t][a] < 0 || m.tets[t][a] >= n) throw InputError("Tetrahedron " + std::to_string(t) + " has an invalid node index.");
    if (!(m.tetVolume(t) > 0))
      throw InputError("Tetrahedron " + std::to_string(t) + " is inverted or flat (volume <= 0).");
  }
  for (const auto& kv : prob.materials) {
    if (!(kv.second.E > 0) || !(kv.second.nu > -1 && kv.second.nu < 0.5))
      throw InputError("Material of tissue " + std::to_string(kv.first) + ": need E > 0 and -1 < Poisson ratio < 0.5.");
    I.Dby[kv.first] = elasticity(kv.second);
  }
  I.D.resize(m.numTets());
  I.mat.resize(m.numTets());
  for (int t = 0; t < m.numTets(); ++t) {
    auto it = prob.materials.find(m.tissue[t]);
    if (it == prob.materials.end())
      throw InputError("No material for tissue label " + std::to_string(m.tissue[t]) + " (tetrahedron " + std::to_string(t) + ").");
    I.mat[t] = &it->second;
    I.D[t] = I.Dby[m.tissue[t]];
  }
  // rebind material pointers to our copy
  for (int t = 0; t < m.numTets(); ++t) I.mat[t] = &I.p.materials.at(m.tissue[t]);

  if (prob.fixed.empty())
    throw InputError("No fixed nodes: the stiffness matrix is singular (the model can move as a rigid body). "
                     "Fix at least the nodes where the model is held (e.g. the costovertebral joints).");
  I.isConstrained.assign(3 * n, 0);
  I.prescribed.setZero(3 * n);
  for (const auto& d : prob.fixed) {
    if (d.node < 0 || d.node >= n || d.dof < 0 || d.dof > 2) throw InputError("Fixed node/dof out of range.");
    I.isConstrained[3 * d.node + d.dof] = 1;
    I.prescribed(3 * d.node + d.dof) = d.value;
  }
  I.fext.setZero(3 * n);
  if (!prob.force.empty()) {
    if (static_cast<int>(prob.force.size()) != n) throw InputError("Force vector size differs from the node count.");
    for (int i = 0; i < n; ++i) I.fext.segment<3>(3 * i) = prob.force[i];
  }
  // nodes used by tets; unused nodes get no dofs
  std::vector<char> used(n, 0);
  for (const auto& e : m.tets)
    for (int a = 0; a < I.nen; ++a) used[e[a]] = 1;
  I.freeIndex.assign(3 * n, -1);
  for (int i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d)
      if (used[i] && !I.isConstrained[3 * i + d]) I.freeIndex[3 * i + d] = I.nFree++;
  if (I.nFree == 0) throw InputError("Every degree of freedom is fixed: nothing to solve.");

  // node adjacency -> lower-triangular pattern of the free dofs
  std::vector<std::vector<int>> adj(n);
  for (const auto& e : m.tets)
    for (int a = 0; a < I.nen; ++a)
      for (int b = 0; b < I.nen; ++b) adj[e[a]].push_back(e[b]);
  std::vector<int> outer(I.nFree + 1, 0);
  std::vector<int> inner;
  inner.reserve(static_cast<size_t>(I.nFree) * 40);
  // compact numbers of the nodes with free dofs (their free dofs are consecutive: node-major numbering)
  std::vector<int> compact(n, -1);
  for (int i = 0; i < n; ++i)
    for (int d = 0; d < 3 && compact[i] < 0; ++d)
      if (I.freeIndex[3 * i + d] >= 0) {
        compact[i] = static_cast<int>(I.nodeFirstDof.size());
        I.nodeFirstDof.push_back(I.freeIndex[3 * i + d]);
      }
  I.nodeFirstDof.push_back(I.nFree);
  I.nodeOuter.assign(1, 0);
  int col = 0;
  for (int i = 0; i < n; ++i) {
    auto& a = adj[i];
    std::sort(a.begin(), a.end());
    a.erase(std::unique(a.begin(), a.end()), a.end());
    if (compact[i] >= 0) {
      for (int j : a)
        if (j >= i && compact[j] >= 0) I.nodeInner.push_back(compact[j]);
      I.nodeOuter.push_back(static_cast<int>(I.nodeInner.size()));
    }
    for (int d = 0; d < 3; ++d) {
      const int fc = I.freeIndex[3 * i + d];
      if (fc < 0) continue;
      std::vector<int> rows;
      for (int j : a)
        for (int e = 0; e < 3; ++e) {
          const int fr = I.freeIndex[3 * j + e];
          if (fr >= fc) rows.push_back(fr);
        }
      std::sort(rows.begin(), rows.end());
      inner.insert(inner.end(), rows.begin(), rows.end());
      outer[++col] = static_cast<int>(inner.size());
    }
    std::vector<int>().swap(a);
  }
  std::vector<double> zeros(inner.size(), 0.0);
  I.K = Eigen::Map<Eigen::SparseMatrix<double>>(I.nFree, I.nFree, static_cast<Eigen::Index>(inner.size()),
                                                 outer.data(), inner.data(), zeros.data());
}

Solver::~Solver() = default;

int Solver::numFreeDofs() const { return impl_->nFree; }

Result Solver::solveLinear(double scale) {
  Impl& I = *impl_;
  Result res;
  res.u = scale * I.prescribed;
  Eigen::VectorXd fint;
  I.assemble(res.u, false, fint);
  Eigen::VectorXd r = I.freePart(scale * I.fext - fint);
  I.factorize(lastFactorSeconds_);
  const Eigen::VectorXd du = I.solveFree(r);
  for (size_t d = 0; d < I.freeIndex.size(); ++d)
    if (I.freeIndex[d] >= 0) res.u(d) += du(I.freeIndex[d]);
  // residual check: catches near-singular systems the factorisation let through. The stiffness is linear,
  // so the free part of the internal force at u is the one at the prescribed displacements plus K du.
  const Eigen::VectorXd Kdu = I.K.selfadjointView<Eigen::Lower>() * du;
  const double rn = (r - Kdu).norm();
  const double ref = std::max({r.norm(), Kdu.norm(), 1e-30});
  if (!(rn <= 1e-6 * ref))
    throw InputError("The linear system could not be solved accurately (relative residual " + std::to_string(rn / ref) +
                     "): the model is nearly singular; fix more nodes.");
  res.increments = 1;
  res.newtonIterations = 1;
  I.stresses(res.u, false, res);
  return res;
}

Result Solver::solveNonlinear(const NewtonOptions& opt, double scale) {
  Impl& I = *impl_;
  if (opt.loadSteps < 1 || opt.maxIterations < 1) throw InputError("Newton: need at least one load step and one iteration.");
  Result res;
  res.nonlinear = true;
  Eigen::VectorXd u = Eigen::VectorXd::Zero(I.fext.size()), fint;
  const double fextNorm = I.freePart(I.fext).norm() * std::abs(scale);
  double lam = 0, dlam = 1.0 / opt.loadSteps;
  int cut = 0;
  while (lam < 1.0 - 1e-12) {
    double target = std::min(1.0, lam + dlam);
    for (double s : opt.stops)
      if (s > lam + 1e-12 && s < target - 1e-12) { target = s; break; }
    Eigen::VectorXd uTrial = u;
    for (size_t d = 0; d < I.freeIndex.size(); ++d)
      if (I.isConstrained[d]) uTrial(d) = target * scale * I.prescribed(d);
    bool converged = false;
    double duNorm = 0, lastRn = 1e300;
    for (int it = 0; it <= opt.maxIterations; ++it) {
      I.assemble(uTrial, true, fint);
      const Eigen::VectorXd r = I.freePart(target * scale * I.fext - fint);
      double reactions = 0;
      for (size_t d = 0; d < I.freeIndex.size(); ++d)
        if (I.isConstrained[d]) reactions += fint(d) * fint(d);
      const double ref = std::max({target * fextNorm, std::sqrt(reactions), 1e-30});
      const double rn = r.norm();
      if (!std::isfinite(rn)) break;
      if (rn <= opt.tolResidual * ref && (it == 0 || duNorm <= opt.tolDisplacement * std::max(uTrial.norm(), 1e-30))) {
        converged = true;
        break;
      }
      if (it == opt.maxIterations) break;
      const bool refactor = !opt.modified || it == 0 || !(rn < lastRn / 3);
      lastRn = rn;
      if (refactor) try {
        I.factorize(lastFactorSeconds_);
        ++res.factorizations;
      } catch (const InputError&) {
        if (it == 0 && lam == 0) throw;  // singular at the undeformed state: a real input problem
        break;                             // lost positive definiteness (buckling/inversion): cut back
      }
      const Eigen::VectorXd du = I.chol.solve(r);
      if (!du.allFinite()) break;
      duNorm = du.norm();
      for (size_t d = 0; d < I.freeIndex.size(); ++d)
        if (I.freeIndex[d] >= 0) uTrial(d) += du(I.freeIndex[d]);
      ++res.newtonIterations;
    }
    if (converged) {
      u = uTrial;
      lam = target;
      ++res.increments;
      if (opt.onIncrement) opt.onIncrement(lam, u);
    } else {
      if (++cut > opt.maxCutbacks) {
        std::ostringstream s;
        s << "The nonlinear (Newton) solve did not converge at load factor " << target << " after " << opt.maxCutbacks
          << " step cut-backs: the load is too large for the model (instability or inverted elements); "
             "reduce the force, use more load steps or check the boundary conditions.";
        throw InputError(s.str());
      }
      dlam *= 0.5;
    }
  }
  res.u = u;
  I.stresses(res.u, true, res);
  return res;
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
