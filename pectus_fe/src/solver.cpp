#include "pectus/fe/solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <sstream>

#include <fstream>
#include <string>
#include <dlfcn.h>
#include <sys/resource.h>
#include <unistd.h>
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
constexpr int kChunkTets = 256;  // the assembly's unit of work: consecutive tets of the dof order (colorChunks)
}  // namespace

void setMinParallelTets(int tets) { gMinParallelTets = std::max(1, tets); }
int minParallelTets() { return gMinParallelTets; }

std::map<int, Material> thesisMaterials(double nuBone, double nuCartilage, MaterialModel model, double eBone,
                                        double eCartilage) {
  return {{1, {eBone, nuBone, model}}, {2, {eCartilage, nuCartilage, model}}, {3, {eBone, nuBone, model}}};
}

const char* materialModelName(MaterialModel m) {
  switch (m) {
    case MaterialModel::NeoHookean: return "neo-hookean";
    case MaterialModel::NeoHookeanDecoupled: return "neo-hookean-ccx";
    default: return "svk";
  }
}

MaterialModel parseMaterialModel(const std::string& name) {
  for (MaterialModel m : {MaterialModel::StVenantKirchhoff, MaterialModel::NeoHookean, MaterialModel::NeoHookeanDecoupled})
    if (name == materialModelName(m)) return m;
  throw InputError("Unknown material model '" + name +
                   "': use svk (St Venant-Kirchhoff), neo-hookean (FEBio's compressible form) or neo-hookean-ccx "
                   "(CalculiX's NEO HOOKE, deviatoric/volumetric split).");
}

namespace {
// D(a, b) += s * (A_IJ B_KL) over Voigt pairs a = (IJ), b = (KL)
inline void addDyad(Eigen::Matrix<double, 6, 6>& D, double s, const Matrix3d& A, const Matrix3d& B) {
  static const int I[6] = {0, 1, 2, 0, 1, 0}, J[6] = {0, 1, 2, 1, 2, 2};
  for (int a = 0; a < 6; ++a)
    for (int b = 0; b < 6; ++b) D(a, b) += s * A(I[a], J[a]) * B(I[b], J[b]);
}
// D(a, b) += s * 1/2 (A_IK A_JL + A_IL A_JK); with A = C^-1 this is -d(C^-1)/dC
inline void addSymProduct(Eigen::Matrix<double, 6, 6>& D, double s, const Matrix3d& A) {
  static const int I[6] = {0, 1, 2, 0, 1, 0}, J[6] = {0, 1, 2, 1, 2, 2};
  for (int a = 0; a < 6; ++a)
    for (int b = 0; b < 6; ++b)
      D(a, b) += s * 0.5 * (A(I[a], I[b]) * A(J[a], J[b]) + A(I[a], J[b]) * A(J[a], I[b]));
}
}  // namespace

double materialResponse(const Material& m, const Matrix3d& F, Matrix3d& S, Eigen::Matrix<double, 6, 6>& D) {
  const double lam = m.E * m.nu / ((1 + m.nu) * (1 - 2 * m.nu)), mu = m.E / (2 * (1 + m.nu));
  const double J = F.determinant();
  D.setZero();
  if (m.model == MaterialModel::StVenantKirchhoff) {
    D.topLeftCorner<3, 3>().setConstant(lam);
    for (int i = 0; i < 3; ++i) D(i, i) += 2 * mu, D(3 + i, 3 + i) = mu;
    const Matrix3d E = 0.5 * (F.transpose() * F - Matrix3d::Identity());
    S = lam * E.trace() * Matrix3d::Identity() + 2 * mu * E;
    return J;
  }
  if (!(J > 0)) {
    S.setConstant(std::numeric_limits<double>::quiet_NaN());
    D.setConstant(std::numeric_limits<double>::quiet_NaN());
    return J;
  }
  const Matrix3d C = F.transpose() * F, Ci = C.inverse(), I = Matrix3d::Identity();
  if (m.model == MaterialModel::NeoHookean) {
    // S = mu (I - C^-1) + lambda ln J C^-1; D = lambda C^-1 x C^-1 + 2 (mu - lambda ln J) dC^-1
    const double lnJ = std::log(J);
    S = mu * (I - Ci) + lam * lnJ * Ci;
    addDyad(D, lam, Ci, Ci);
    addSymProduct(D, 2 * (mu - lam * lnJ), Ci);
  } else {
    // isochoric: S = mu J^(-2/3) (I - I1/3 C^-1), D = 2/3 mu J^(-2/3) [I1 dC^-1 + I1/3 C^-1 x C^-1 - I x C^-1 - C^-1 x I]
    // volumetric U = K/2 (J - 1)^2 (= (J - 1)^2 / D1): p = K (J - 1), S = J p C^-1,
    // D = J (p + J K) C^-1 x C^-1 - 2 J p dC^-1   (Holzapfel, Nonlinear Solid Mechanics, 6.4)
    const double K = m.E / (3 * (1 - 2 * m.nu)), I1 = C.trace(), j23 = std::pow(J, -2.0 / 3.0), p = K * (J - 1);
    S = mu * j23 * (I - I1 / 3 * Ci) + J * p * Ci;
    const double c = 2.0 / 3.0 * mu * j23;
    addSymProduct(D, c * I1 - 2 * J * p, Ci);
    addDyad(D, c * I1 / 3 + J * (p + J * K), Ci, Ci);
    addDyad(D, -c, I, Ci);
    addDyad(D, -c, Ci, I);
  }
  return J;
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
// cage's systems (small supernodes, ~1e8-1e9 flops) is 5-10x slower than on one BLAS thread (a 127k-dof
// cage: 2.94 s against 0.27 s). So the BLAS gets one thread for small factorisations and
// OpenMP's thread count from kBlasThreadFlops on (the long cantilever benchmark: 2e11 flops). The call is
// looked up at run time (the BLAS behind libblas.so.3 is chosen by Debian's alternatives; the reference
// BLAS has no threads to set). PECTUS_BLAS_THREADS=n forces n.
constexpr double kBlasThreadFlops = 2e10;

// an OpenBLAS function in the BLAS this process has loaded; null for another BLAS
void* openBlasFunction(const char* name) {
  for (const char* lib : {"libopenblas.so.0", "libblas.so.3", "libopenblas.so"})
    if (void* h = dlopen(lib, RTLD_LAZY | RTLD_NOLOAD))
      if (void* f = dlsym(h, name)) return f;
  return dlsym(RTLD_DEFAULT, name);
}

void setBlasThreads(double flops) {
  using SetThreads = void (*)(int);
  static const auto set = reinterpret_cast<SetThreads>(openBlasFunction("openblas_set_num_threads"));
  if (!set) return;
  int n = flops >= kBlasThreadFlops ? omp_get_max_threads() : 1;
  if (const char* e = std::getenv("PECTUS_BLAS_THREADS")) n = std::max(1, std::atoi(e));
  set(n);
}

}  // namespace

void restBlasThreads() {
  using Shutdown = int (*)();
  if (const auto shutdown = reinterpret_cast<Shutdown>(openBlasFunction("blas_thread_shutdown_"))) shutdown();
}

namespace {

// Bytes a new allocation can take without swapping or the kernel's out-of-memory killer: the kernel's
// MemAvailable, bounded by the process' address-space limit (ulimit -v) and by PECTUS_FE_MEMORY_GB when
// set (a share of a machine that runs other jobs). 0 if none is known.
double availableBytes() {
  double avail = 0;
  std::ifstream meminfo("/proc/meminfo");
  for (std::string key; meminfo >> key;) {
    double kb = 0;
    meminfo >> kb;
    meminfo.ignore(64, '\n');
    if (key == "MemAvailable:") {
      avail = kb * 1024.0;
      break;
    }
  }
  if (!(avail > 0)) avail = double(::sysconf(_SC_AVPHYS_PAGES)) * double(::sysconf(_SC_PAGESIZE));
  rlimit as{};
  if (::getrlimit(RLIMIT_AS, &as) == 0 && as.rlim_cur != RLIM_INFINITY) avail = std::min(avail, double(as.rlim_cur));
  if (const char* e = std::getenv("PECTUS_FE_MEMORY_GB"))
    if (const double gb = std::atof(e); gb > 0) avail = avail > 0 ? std::min(avail, gb * 1e9) : gb * 1e9;
  return avail;
}

// The symbolic analysis knows the size of the Cholesky factor before any of it is allocated: a model
// whose factor does not fit in the memory left is refused here, with what to change, instead of being
// killed by the operating system later in the solve. The factor may take half of what is available:
// the tangent matrix, its element blocks, the Newton vectors and the results need the rest.
constexpr double kFactorShareOfMemory = 0.5;
void requireFactorFits(double factorEntries, int freeDofs) {
  const double need = factorEntries * sizeof(double) / kFactorShareOfMemory, avail = availableBytes();
  if (!(avail > 0) || need <= avail) return;
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(1);
  s << "The FE model is too large for the memory of this machine: its stiffness matrix (" << freeDofs
    << " free unknowns) needs about " << need / 1e9 << " GB to factorise and solve, and " << avail / 1e9
    << " GB are available. Make fewer, larger tetrahedra: a larger edge length of the cage surface, a maximum tet "
       "volume, tet quality 0 (no refinement), or TET4 elements.";
  throw ModelTooLarge(s.str());
}

class Cholmod : public Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> {
 public:
  double rcond() { return m_cholmodFactor ? cholmod_rcond(m_cholmodFactor, &cholmod()) : 0.0; }

  // Fill-reducing ordering of the graph of the nodes (lower-triangular pattern `outer`/`inner`, compact
  // node numbers) instead of the dofs: the graph is 3x smaller (9x fewer edges), and no separator cuts
  // through a node. CHOLMOD's own default strategy picks the method: AMD, then METIS where AMD's fill is
  // large, keeping the one with fewer flops (the rib cage's thin bones: AMD, 30 % fewer flops than METIS
  // and found in 0.02 s instead of 0.95 s; a solid block: METIS). `method` forces one (CHOLMOD_AMD ...).
  // The order comes back postordered (children before parents). Empty if CHOLMOD failed.
  std::vector<int> orderNodes(std::vector<int>& outer, std::vector<int>& inner, int method = -1) {
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
  int nodeOrdering = -1;  // the method orderNodes used (CHOLMOD_AMD, CHOLMOD_METIS, ...)

  // entries of the numeric factor the analysis prepared (a supernodal factor stores its supernodes' full
  // columns: more than the nonzeros CHOLMOD counts)
  double factorEntries() {
    const cholmod_factor* L = m_cholmodFactor;
    if (!L) return 0;
    return std::max(double(cholmod().lnz), L->is_super ? double(L->xsize) : 0.0);
  }

  // Symbolic analysis of K (lower triangle) whose dofs are already numbered in the fill-reducing order,
  // postordered (orderNodes): CHOLMOD's natural ordering without its postorder, so that it factorises K
  // as it is stored. With an ordering of its own, CHOLMOD makes two scattered transposes of K per
  // factorisation (and more in the analysis): 0.5 s of the rib cage's 4 s analysis. False if CHOLMOD failed.
  bool analyzeInOrder(const Eigen::SparseMatrix<double>& K) {
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
};

}  // namespace

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
  std::vector<Gauss> quad;                           // the element's quadrature rule
  std::vector<Eigen::Matrix<double, 10, 3>> quadDN;  // reference shape derivatives at its points
  Eigen::Matrix<double, 10, 3> centroidDN;           // and at the centroid (stresses)

  void setOrder(int order) {
    quad = rule(order);
    quadDN.resize(quad.size());
    for (std::size_t q = 0; q < quad.size(); ++q) shapeDerivs(order, quad[q].L, quadDN[q]);
    const double c[4] = {0.25, 0.25, 0.25, 0.25};
    shapeDerivs(order, c, centroidDN);
  }

  Impl() {
    chol.cholmod().print = 0;  // errors are reported by exceptions, not on stderr
    if (const char* o = std::getenv("PECTUS_FE_ORDERING")) {  // experiments: amd | metis | nesdis
      orderByNodes = false;
      chol.cholmod().nmethods = 1;
      const std::string s(o);
      chol.cholmod().method[0].ordering = s == "metis" ? CHOLMOD_METIS : s == "nesdis" ? CHOLMOD_NESDIS : CHOLMOD_AMD;
    }
  }

  // element gradients dN/dX at a point with reference derivatives dN (shapeDerivs), returns det(J) * w.
  // Fixed sizes throughout: a dynamic topRows(nen) product would go through Eigen's blocked GEMM kernel.
  template <int NEN>
  double gradientsT(int t, const Eigen::Matrix<double, 10, 3>& dN10, double w, Eigen::Matrix<double, NEN, 3>& G) const {
    const Eigen::Matrix<double, NEN, 3> dN = dN10.template topRows<NEN>();
    Matrix3d J = Matrix3d::Zero();
    for (int a = 0; a < NEN; ++a) J.noalias() += m->nodes[m->tets[t][a]] * dN.row(a);
    const double det = J.determinant();
    G.noalias() = dN.lazyProduct(J.inverse());
    return det * w;
  }

  // assemble tangent (free-free lower; tangent = false: K is left as it is) and internal forces (all
  // dofs) at displacement u
  void assemble(const Eigen::VectorXd& u, bool nonlinear, Eigen::VectorXd& fint, bool tangent = true) {
    if (nen == 10)
      assembleT<10>(u, nonlinear, fint, tangent);
    else
      assembleT<4>(u, nonlinear, fint, tangent);
  }

  template <int NEN>
  void assembleT(const Eigen::VectorXd& u, bool nonlinear, Eigen::VectorXd& fint, bool tangent) {
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
  void assembleTet(int t, const Eigen::VectorXd& u, bool nonlinear, double* val, double* fi) const {
    constexpr int ND = 3 * NEN;
    Eigen::Matrix<double, ND, ND> Ke = Eigen::Matrix<double, ND, ND>::Zero();
    Eigen::Matrix<double, ND, 1> fe = Eigen::Matrix<double, ND, 1>::Zero();
    Eigen::Matrix<double, NEN, 3> G, ue;
    for (int a = 0; a < NEN; ++a) ue.row(a) = u.template segment<3>(3 * m->tets[t][a]).transpose();
    const bool hyper = nonlinear && mat[t]->model != MaterialModel::StVenantKirchhoff;
    Eigen::Matrix<double, 6, 6> Dq;  // the hyperelastic tangent at a quadrature point
    for (std::size_t q = 0; q < quad.size(); ++q) {
      const double w = gradientsT<NEN>(t, quadDN[q], quad[q].w, G);
      const Matrix3d H = ue.transpose() * G;  // du_i/dX_j
      Matrix3d F = Matrix3d::Identity();
      Matrix3d S;
      if (hyper) {
        F += H;
        materialResponse(*mat[t], F, S, Dq);  // NaN when inverted: the residual is not finite, Newton backs off
      } else {
        Matrix3d E;
        if (nonlinear) {
          F += H;
          E = 0.5 * (H + H.transpose() + H.transpose() * H);
        } else {
          E = 0.5 * (H + H.transpose());
        }
        const Eigen::Matrix<double, 6, 1> Sv = *D[t] * voigt(E, true);
        S << Sv(0), Sv(3), Sv(5), Sv(3), Sv(1), Sv(4), Sv(5), Sv(4), Sv(2);
      }
      const auto& Dm = hyper ? Dq : *D[t];
      const Matrix3d P = F * S;  // first Piola (linear: sigma)
      Eigen::Matrix<double, 6, ND> B;
      for (int a = 0; a < NEN; ++a) {
        const Vector3d Ga = G.row(a).transpose();
        fe.template segment<3>(3 * a) += w * P * Ga;
        if (!val) continue;
        for (int i = 0; i < 3; ++i) {
          B(0, 3 * a + i) = F(i, 0) * Ga(0);
          B(1, 3 * a + i) = F(i, 1) * Ga(1);
          B(2, 3 * a + i) = F(i, 2) * Ga(2);
          B(3, 3 * a + i) = F(i, 0) * Ga(1) + F(i, 1) * Ga(0);
          B(4, 3 * a + i) = F(i, 1) * Ga(2) + F(i, 2) * Ga(1);
          B(5, 3 * a + i) = F(i, 0) * Ga(2) + F(i, 2) * Ga(0);
        }
      }
      if (!val) continue;
      const Eigen::Matrix<double, 6, ND> DB = (w * Dm) * B;
      Ke.noalias() += B.transpose().lazyProduct(DB);
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
    if (!val) return;
    // the element's dofs by free index (constrained ones, -1, first): a column's rows are then the dofs
    // after it, ascending, found by one forward walk along the column (a binary search per entry
    // mispredicts most of its branches)
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

  // greedy colouring of the chunks of kChunkTets consecutive tets of `order` (deterministic): each chunk
  // takes the lowest colour that no chunk at its nodes has yet, so no two chunks of a colour share a
  // node. Corners suffice: tets sharing a TET10 mid-edge node share that edge's corners. The colours at
  // a node are bits of a 64-bit mask for the first 64 colours (PECTUS_FE_VERBOSE prints how many), then a list.
  static std::vector<std::vector<int>> colorChunks(const TetMesh& mesh, const std::vector<int>& order) {
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
    if (chol.info() != Eigen::Success)
      throw SolverFailure(
          "The stiffness matrix is singular or not positive definite: the model is not held enough (fix more "
          "nodes so that every part of the mesh is connected to a fixed node), or an element is inverted.");
    const double rc = chol.rcond();
    if (!(rc > 1e-15)) {
      std::ostringstream s;
      s << "The stiffness matrix is numerically singular (reciprocal condition estimate " << rc
        << "): the fixed nodes do not prevent a rigid-body motion of some part of the model; fix more nodes "
           "(at least three non-collinear nodes per connected part).";
      throw SolverFailure(s.str());
    }
  }

  Eigen::VectorXd solveFree(const Eigen::VectorXd& rhs) {
    Eigen::VectorXd x = chol.solve(rhs);
    if (!x.allFinite())
      throw SolverFailure("The linear solve produced non-finite displacements (singular stiffness matrix): fix more nodes.");
    return x;
  }

  void stresses(const Eigen::VectorXd& u, bool nonlinear, Result& res) const {
    if (nen == 10)
      stressesT<10>(u, nonlinear, res);
    else
      stressesT<4>(u, nonlinear, res);
  }

  // stress and strain at the tet centroid
  template <int NEN>
  void stressesT(const Eigen::VectorXd& u, bool nonlinear, Result& res) const {
    const int nt = m->numTets();
    res.vonMises.assign(nt, 0.0);
    res.eqStrain.assign(nt, 0.0);
#pragma omp parallel for schedule(static) if (nt >= gMinParallelTets)
    for (int t = 0; t < nt; ++t) {
      Eigen::Matrix<double, NEN, 3> G, ue;
      for (int a = 0; a < NEN; ++a) ue.row(a) = u.segment<3>(3 * m->tets[t][a]).transpose();
      gradientsT<NEN>(t, centroidDN, 1.0, G);
      const Matrix3d H = ue.transpose().lazyProduct(G);
      Matrix3d E = nonlinear ? Matrix3d(0.5 * (H + H.transpose() + H.transpose() * H)) : Matrix3d(0.5 * (H + H.transpose()));
      Matrix3d S;
      if (nonlinear && mat[t]->model != MaterialModel::StVenantKirchhoff) {
        Eigen::Matrix<double, 6, 6> Dq;
        materialResponse(*mat[t], Matrix3d::Identity() + H, S, Dq);
      } else {
        const Eigen::Matrix<double, 6, 1> Sv = *D[t] * voigt(E, true);
        S << Sv(0), Sv(3), Sv(5), Sv(3), Sv(1), Sv(4), Sv(5), Sv(4), Sv(2);
      }
      if (nonlinear) {
        const Matrix3d F = Matrix3d::Identity() + H;
        S = F * S * F.transpose() / F.determinant();
      }
      res.vonMises[t] = vonMisesOf(S);
      res.eqStrain[t] = eqStrainOf(E, mat[t]->nu);
    }
  }

  // min det F over the tets' quadrature points and centroids at u (nonlinear kinematics): the first tet
  // where it is not positive, as a message naming it, its tissue and its place; empty if none
  std::string invertedAt(const Eigen::VectorXd& u) const {
    if (u.size() != fext.size() || !u.allFinite()) return {};
    const int nt = m->numTets();
    for (int t = 0; t < nt; ++t) {
      double minJ = std::numeric_limits<double>::infinity();
      auto check = [&](const Eigen::Matrix<double, 10, 3>& dN) {
        Matrix3d H = Matrix3d::Zero();
        if (nen == 10) {
          Eigen::Matrix<double, 10, 3> G;
          gradientsT<10>(t, dN, 1.0, G);
          for (int a = 0; a < 10; ++a) H += u.segment<3>(3 * m->tets[t][a]) * G.row(a);
        } else {
          Eigen::Matrix<double, 4, 3> G;
          gradientsT<4>(t, dN, 1.0, G);
          for (int a = 0; a < 4; ++a) H += u.segment<3>(3 * m->tets[t][a]) * G.row(a);
        }
        minJ = std::min(minJ, (Matrix3d::Identity() + H).determinant());
      };
      check(centroidDN);
      for (const auto& dN : quadDN) check(dN);
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
        << materialModelName(mat[t]->model) << ", E " << mat[t]->E << " MPa) at (" << c.x() << ", " << c.y() << ", " << c.z()
        << ") mm, displaced by (" << uc.x() << ", " << uc.y() << ", " << uc.z() << ") mm (det F = " << minJ << ")";
      return o.str();
    }
    return {};
  }

  // --- the problem's setup (Solver's constructor), step by step ---

  // every tet references existing nodes and has a positive volume; a TET10 whose mid-edge nodes lie far
  // from its edges' midpoints can fold inside although its corners do not: its Jacobian must be positive at
  // every quadrature point and at the centroid (where the stresses are taken), else its stiffness and
  // stresses are meaningless (NaN stresses)
  void checkTets() const {
    const int n = m->numNodes();
    for (int t = 0; t < m->numTets(); ++t) {
      for (int a = 0; a < nen; ++a)
        if (m->tets[t][a] < 0 || m->tets[t][a] >= n) throw TopologyError("Tetrahedron " + std::to_string(t) + " has an invalid node index.");
      if (!(m->tetVolume(t) > 0))
        throw TopologyError("Tetrahedron " + std::to_string(t) + " is inverted or flat (volume <= 0).");
      if (nen == 10) {
        Eigen::Matrix<double, 10, 3> G;
        bool ok = gradientsT<10>(t, centroidDN, 1.0, G) > 0;
        for (std::size_t q = 0; q < quad.size() && ok; ++q) ok = gradientsT<10>(t, quadDN[q], 1.0, G) > 0;
        if (!ok)
          throw TopologyError("Tetrahedron " + std::to_string(t) +
                           " (quadratic) folds inside: its mid-edge nodes are too far from its edges' midpoints (the "
                           "Jacobian is not positive everywhere in it). Use straight-sided quadratic tets or refine there.");
      }
    }
  }

  // the elasticity matrix of each tissue's material, and per tet its material (in our copy p) and matrix
  void bindMaterials(const Problem& prob) {
    for (const auto& kv : prob.materials) {
      if (!(kv.second.E > 0) || !(kv.second.nu > -1 && kv.second.nu < 0.5))
        throw InputError("Material of tissue " + std::to_string(kv.first) + ": need E > 0 and -1 < Poisson ratio < 0.5.");
      Dby[kv.first] = elasticity(kv.second);
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
  void setLoads(const Problem& prob) {
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

  // node adjacency (compressed rows, sorted, with the node itself); nodes without tets have no row entries
  void nodeAdjacency(std::vector<int>& adjOuter, std::vector<int>& adj) const {
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

  // the nodes with a free dof, compactly numbered (the ordering's graph): compact per node (-1: none),
  // nodeOf per compact number
  void freeNodes(const std::vector<int>& adjOuter, std::vector<int>& compact, std::vector<int>& nodeOf) const {
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
  std::vector<int> orderFreeNodes(const std::vector<int>& adjOuter, const std::vector<int>& adj,
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
  std::vector<int> numberFreeDofs(const std::vector<int>& order, const std::vector<int>& nodeOf) {
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

  // lower-triangular pattern of K (zero values): the column of a free dof holds the free dofs at or after it
  // of the node's neighbours; with the neighbours sorted by rank the rows come out sorted
  void stiffnessPattern(const std::vector<int>& order, const std::vector<int>& nodeOf, const std::vector<int>& adjOuter,
                        const std::vector<int>& adj, const std::vector<int>& rank) {
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
  void orderTets(const std::vector<int>& rank) {
    std::vector<int> first(std::size_t(m->numTets()));
    for (int t = 0; t < m->numTets(); ++t) {
      int r = std::numeric_limits<int>::max();
      for (int a = 0; a < 4; ++a) r = std::min(r, rank[std::size_t(m->tets[std::size_t(t)][a])]);
      first[std::size_t(t)] = r;
    }
    tetOrder.resize(first.size());
    for (std::size_t t = 0; t < first.size(); ++t) tetOrder[t] = static_cast<int>(t);
    std::stable_sort(tetOrder.begin(), tetOrder.end(), [&](int x, int y) { return first[std::size_t(x)] < first[std::size_t(y)]; });
  }

  // the Newton options must allow a path: at least one step and iteration, a usable line search and step control
  static void checkNewtonOptions(const NewtonOptions& opt) {
    if (opt.loadSteps < 1 || opt.maxIterations < 1) throw InputError("Newton: need at least one load step and one iteration.");
    if (opt.lineSearch && !(opt.lineSearchTol > 0 && opt.lineSearchSteps >= 1))
      throw InputError("Newton: the line search needs a tolerance > 0 and at least one step.");
    if (opt.adaptiveSteps && !(opt.targetIterations >= 1 && opt.maxStepGrowth >= 1))
      throw InputError("Newton: automatic steps need target iterations >= 1 and a maximum growth >= 1.");
  }

  // a Newton path's state and its steps (path): increments of the load factor (or displacement fraction), each
  // solved by Newton iterations from a trial state
  struct NewtonPath {
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
      Eigen::VectorXd uTrial = trialStart(target);
      double Lt = L;  // load factor of the trial state (displacement control)
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

    // the converged state with the prescribed displacements at the target (none under displacement control)
    Eigen::VectorXd trialStart(double target) const {
      Eigen::VectorXd uTrial = u;
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

    // Newton iterations from uTrial (load factor Lt) at the target; true if they converged (it: their count)
    bool iterate(double target, Eigen::VectorXd& uTrial, double& Lt, int& it) {
      double duNorm = 0, lastRn = 1e300;
      for (; it <= opt.maxIterations; ++it) {
        const Eigen::VectorXd r = residual(uTrial, factorAt(Lt, target), true);
        double reactions = 0;
        for (size_t d = 0; d < I.freeIndex.size(); ++d)
          if (I.isConstrained[d]) reactions += fint(d) * fint(d);
        const double ref = std::max({ctrl ? std::abs(Lt) * fFree.norm() : target * fextNorm, std::sqrt(reactions), 1e-30});
        const double rn = r.norm();
        if (opt.onIteration) opt.onIteration(res.increments, it, rn);
        if (!std::isfinite(rn)) {
          if (inversion.empty()) inversion = I.invertedAt(uTrial);
          return false;
        }
        const double g = ctrl ? ctrl->dot(I.freePart(uTrial)) - target * dTarget : 0.0;  // constraint violation
        if (rn <= opt.tolResidual * ref && std::abs(g) <= opt.tolDisplacement * std::abs(dTarget) &&
            (it == 0 || duNorm <= opt.tolDisplacement * std::max(uTrial.norm(), 1e-30))) {
          fintConverged = fint;
          return true;
        }
        if (it == opt.maxIterations) return false;
        const bool refactor = !opt.modified || it == 0 || !(rn < lastRn / 3);
        lastRn = rn;
        Eigen::VectorXd du;
        double dL = 0;
        if (!newtonStep(refactor, it, uTrial, r, g, du, dL)) return false;
        duNorm = du.norm();
        const double a = opt.lineSearch ? lineSearch(uTrial, Lt, target, r, du, dL) : 1;
        for (size_t d = 0; d < I.freeIndex.size(); ++d)
          if (I.freeIndex[d] >= 0) uTrial(d) += a * du(I.freeIndex[d]);
        Lt += a * dL;
        ++res.newtonIterations;
      }
      return false;
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
        const Eigen::VectorXd b = I.chol.solve(fFree);
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

  // Newton with load increments (ctrl null: load factor target * scale on the forces and prescribed
  // displacements) or displacement control (ctrl: free-dof weights w, w . u stepped to target; the load
  // factor is the extra unknown of a bordered system)
  Result path(const NewtonOptions& opt, double scale, const Eigen::VectorXd* ctrl, double dTarget, double& factorSeconds) {
    checkNewtonOptions(opt);
    NewtonPath np(*this, opt, scale, ctrl, dTarget, factorSeconds);
    while (!np.done()) np.increment();
    return np.result();
  }
};

Solver::Solver(const Problem& prob) : impl_(std::make_unique<Impl>()) {
  Impl& I = *impl_;
  I.p = prob;
  if (!prob.mesh) throw InputError("FE problem without a mesh.");
  const TetMesh& m = *prob.mesh;
  I.m = &m;
  I.nen = m.nodesPerTet();
  I.setOrder(m.order);
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
