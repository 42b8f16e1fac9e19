// Verification of the pectus_fe solvers: patch tests, cantilever vs beam theory, Lame cylinder,
// nonlinear vs linear, singular systems and non-converging Newton solves.
#include <gtest/gtest.h>

#include <dlfcn.h>
#include <omp.h>
#include <sys/resource.h>
#include <unistd.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <cstring>
#include <random>

#include "pectus/errors.h"
#include "pectus/fe/solver.h"
#include "../src/element.h"
#include "../src/materials/material.h"

using namespace pectus::fe;
using Eigen::Vector3d;

namespace {

TetMesh perturbedBox(int order, unsigned seed) {
  TetMesh m = structuredBox(2, 3, 4, 3, 3, 3, 1);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> d(-0.15, 0.15);
  for (auto& p : m.nodes) {
    const bool interior = p.x() > 1e-9 && p.x() < 2 - 1e-9 && p.y() > 1e-9 && p.y() < 3 - 1e-9 && p.z() > 1e-9 && p.z() < 4 - 1e-9;
    if (interior) {
      const double dz = d(rng), dy = d(rng), dx = d(rng);  // fixed order (gcc's): argument order is unspecified
      p += Vector3d(dx * 2 / 3, dy, dz * 4 / 3);
    }
  }
  return order == 2 ? toQuadratic(m) : m;
}

void patchTest(int order) {
  const TetMesh m = perturbedBox(order, 7);
  Eigen::Matrix3d A;
  A << 1e-3, 2e-4, -3e-4, 5e-4, -2e-3, 1e-4, -4e-4, 3e-4, 1.5e-3;
  const Vector3d c(0.01, -0.02, 0.03);
  Problem p;
  p.mesh = &m;
  p.materials = {{1, {1000.0, 0.3}}};
  for (int i = 0; i < m.numNodes(); ++i) {
    const Vector3d& x = m.nodes[i];
    const bool boundary = x.x() < 1e-9 || x.x() > 2 - 1e-9 || x.y() < 1e-9 || x.y() > 3 - 1e-9 || x.z() < 1e-9 || x.z() > 4 - 1e-9;
    if (!boundary) continue;
    const Vector3d u = A * x + c;
    for (int d = 0; d < 3; ++d) p.fixed.push_back({i, d, u(d)});
  }
  const Result r = solveLinear(p);
  double maxErr = 0;
  int interior = 0;
  for (int i = 0; i < m.numNodes(); ++i) {
    maxErr = std::max(maxErr, (r.displacement(i) - (A * m.nodes[i] + c)).norm());
    const Vector3d& x = m.nodes[i];
    interior += x.x() > 1e-9 && x.x() < 2 - 1e-9 && x.y() > 1e-9 && x.y() < 3 - 1e-9 && x.z() > 1e-9 && x.z() < 4 - 1e-9;
  }
  EXPECT_GT(interior, 3);
  EXPECT_LT(maxErr, 1e-12) << "order " << order;
  // constant stress everywhere
  for (size_t t = 1; t < r.vonMises.size(); ++t) EXPECT_NEAR(r.vonMises[t], r.vonMises[0], 1e-9);
  EXPECT_GT(r.vonMises[0], 0.1);
}

struct Beam { double tip; TetMesh mesh; };
constexpr double kE = 11500, kNu = 0.3, kL = 100, kB = 10;

// 10 x 10 x 100 mm cantilever along z, clamped at z = 0, uniform shear traction on the tip face (total P along y)
Problem cantilever(const TetMesh& m, double P) {
  Problem p;
  p.mesh = &m;
  p.materials = {{1, {kE, kNu}}};
  for (int i = 0; i < m.numNodes(); ++i)
    if (m.nodes[i].z() < 1e-9) p.fixNode(i);
  std::vector<BoundaryFace> tip;
  for (const auto& f : boundaryFaces(m)) {
    bool all = true;
    for (int k = 0; k < 3; ++k) all = all && m.nodes[f.n[k]].z() > kL - 1e-9;
    if (all) tip.push_back(f);
  }
  p.force = tractionLoads(m, tip, Vector3d(0, P / (kB * kB), 0));
  return p;
}

double tipDeflection(const TetMesh& m, const Result& r, double length = kL) {
  double s = 0;
  int n = 0;
  for (int i = 0; i < m.numNodes(); ++i)
    if (m.nodes[i].z() > length - 1e-9) s += r.displacement(i).y(), ++n;
  return s / n;
}

double timoshenko(double P) {
  const double I = kB * kB * kB * kB / 12, A = kB * kB, G = kE / (2 * (1 + kNu));
  const double kappa = 10 * (1 + kNu) / (12 + 11 * kNu);
  return P * kL * kL * kL / (3 * kE * I) + P * kL / (kappa * G * A);
}

}  // namespace

TEST(FeSolver, PatchTestTet4) { patchTest(1); }

// the assembly sums in the same order whatever the thread count: bit-identical displacements (TET10,
// enough tets for several threads to share the assembly; nonlinear: assembled at every Newton iteration)
TEST(FeSolver, SameResultWithOneAndTwoThreads) {
  const TetMesh q = toQuadratic(structuredBox(kB, kB, kL, 3, 3, 30, 1));
  const int grain = minParallelTets();
  setMinParallelTets(1);  // every colour in parallel (by default this small mesh runs in one thread)
  std::vector<Eigen::VectorXd> u;
  for (int threads : {1, 2}) {
    omp_set_num_threads(threads);
    Problem p = cantilever(q, 5.0);
    NewtonOptions o;
    o.loadSteps = 1;
    u.push_back(solveNonlinear(p, o).u);
  }
  omp_set_num_threads(omp_get_num_procs());
  setMinParallelTets(grain);
  ASSERT_EQ(u[0].size(), u[1].size());
  EXPECT_EQ(std::memcmp(u[0].data(), u[1].data(), sizeof(double) * std::size_t(u[0].size())), 0);
  EXPECT_GT(u[0].norm(), 0.0);
}
TEST(FeSolver, PatchTestTet10) { patchTest(2); }

// the default ordering (CHOLMOD's AMD-or-METIS choice on the node graph, each node's free dofs kept
// together) solves the same system as CHOLMOD's own orderings of the dofs: same displacements to round-off,
// also with nodes that have only some dofs fixed (rollers on the side y = 0: their x and z dofs stay free)
TEST(FeSolver, NodeOrderingSolvesTheSameSystemAsCholmodsOwn) {
  const TetMesh q = toQuadratic(structuredBox(kB, kB, kL, 2, 2, 16, 1));
  Problem p = cantilever(q, 20.0);
  int rollers = 0;
  for (int i = 0; i < q.numNodes(); ++i)
    if (q.nodes[i].y() < 1e-9 && q.nodes[i].z() > 1e-9 && q.nodes[i].z() < 30) p.fixed.push_back({i, 1, 0.0}), ++rollers;
  ASSERT_GT(rollers, 5);
  const Eigen::VectorXd byNodes = solveLinear(p).u;
  for (const char* ordering : {"amd", "metis"}) {
    setenv("PECTUS_FE_ORDERING", ordering, 1);
    const Eigen::VectorXd own = solveLinear(p).u;
    unsetenv("PECTUS_FE_ORDERING");
    ASSERT_EQ(own.size(), byNodes.size());
    EXPECT_LT((own - byNodes).norm(), 1e-10 * byNodes.norm()) << ordering;
  }
  EXPECT_GT(byNodes.norm(), 0.1);
}

// a factor that does not fit in the memory left is refused after the symbolic analysis, before the
// factorisation allocates it, with what to change; the same model solves where the memory suffices
TEST(FeSolver, ModelWhoseFactorDoesNotFitIsRefusedBeforeFactorising) {
  const TetMesh q = toQuadratic(structuredBox(kB, kB, kL, 2, 2, 16, 1));
  const Problem p = cantilever(q, 20.0);
  setenv("PECTUS_FE_MEMORY_GB", "0.0001", 1);  // 100 kB
  std::string what;
  try {
    solveLinear(p);
  } catch (const ModelTooLarge& e) {
    what = e.what();
  }
  setenv("PECTUS_FE_MEMORY_GB", "4", 1);
  const Eigen::VectorXd u = solveLinear(p).u;
  unsetenv("PECTUS_FE_MEMORY_GB");
  EXPECT_NE(what.find("too large for the memory"), std::string::npos) << what;
  EXPECT_NE(what.find("0.0 GB are available"), std::string::npos) << what;
  EXPECT_NE(what.find("TET4"), std::string::npos) << what;
  EXPECT_GT(u.norm(), 0.1);
}

TEST(FeSolver, CantileverVsBeamTheory) {
  const double P = 20.0;
  const double ref = timoshenko(P);
  const TetMesh lin = structuredBox(kB, kB, kL, 2, 2, 20, 1);
  const TetMesh quad = toQuadratic(lin);
  const double d4 = tipDeflection(lin, solveLinear(cantilever(lin, P)));
  const double d10 = tipDeflection(quad, solveLinear(cantilever(quad, P)));
  const TetMesh lin4 = structuredBox(kB, kB, kL, 4, 4, 40, 1);
  const double d4f = tipDeflection(lin4, solveLinear(cantilever(lin4, P)));
  std::printf("[cantilever] Timoshenko %.5f mm, Euler-Bernoulli %.5f mm\n", ref, P * kL * kL * kL / (3 * kE * kB * kB * kB * kB / 12));
  std::printf("[cantilever] TET10 2x2x20: %.5f (ratio %.4f)  TET4 2x2x20: %.5f (ratio %.4f)  TET4 4x4x40: %.5f (ratio %.4f)\n",
              d10, d10 / ref, d4, d4 / ref, d4f, d4f / ref);
  EXPECT_NEAR(d10 / ref, 1.0, 0.02);
  EXPECT_LT(d4 / ref, 0.9);  // linear tets lock
  EXPECT_GT(d4f, d4);        // and converge from below
  EXPECT_LT(d4f / ref, 1.0);
}

TEST(FeSolver, ThickCylinderVsLame) {
  // quarter of a thick cylinder a = 10, b = 20, plane strain (u_z = 0 on all nodes), internal pressure p
  const double a = 10, b = 20, pr = 5.0, E = 1000, nu = 0.3;
  const double half = M_PI / 2;
  TetMesh lin = structuredBox(1, 1, 1, 6, 12, 1, 1, [&](const Vector3d& q) {
    const double r = a + (b - a) * q.x(), th = half * q.y();
    return Vector3d(r * std::cos(th), r * std::sin(th), 2.0 * q.z());
  });
  const TetMesh m = toQuadratic(lin);
  Problem p;
  p.mesh = &m;
  p.materials = {{1, {E, nu}}};
  for (int i = 0; i < m.numNodes(); ++i) {
    const Vector3d& x = m.nodes[i];
    p.fixed.push_back({i, 2, 0.0});
    if (std::abs(x.x()) < 1e-9) p.fixed.push_back({i, 0, 0.0});
    if (std::abs(x.y()) < 1e-9) p.fixed.push_back({i, 1, 0.0});
  }
  std::vector<BoundaryFace> inner;
  for (const auto& f : boundaryFaces(m)) {
    bool all = true;
    for (int k = 0; k < 3; ++k) all = all && std::abs(m.nodes[f.n[k]].head<2>().norm() - a) < 1e-6;
    if (all) inner.push_back(f);
  }
  ASSERT_EQ(inner.size(), 24u);
  p.force = pressureLoads(m, inner, pr);
  const Result r = solveLinear(p);
  const double A = pr * a * a / (b * b - a * a), B = pr * a * a * b * b / (b * b - a * a);
  auto lame = [&](double rr) { return (1 + nu) / E * ((1 - 2 * nu) * A * rr + B / rr); };
  double worst = 0;
  for (int i = 0; i < m.numNodes(); ++i) {
    const double rr = m.nodes[i].head<2>().norm();
    if (std::abs(rr - a) > 1e-6 && std::abs(rr - b) > 1e-6) continue;
    const double ur = r.displacement(i).head<2>().dot(m.nodes[i].head<2>()) / rr;
    worst = std::max(worst, std::abs(ur / lame(rr) - 1));
  }
  std::printf("[lame] u_r(a) exact %.6f, u_r(b) exact %.6f, worst relative error %.4f\n", lame(a), lame(b), worst);
  EXPECT_LT(worst, 0.03);
}

TEST(FeSolver, NonlinearMatchesLinearForSmallLoadsAndStiffensForLarge) {
  const TetMesh m = structuredBox(kB, kB, kL, 2, 2, 20, 1);
  const TetMesh q = toQuadratic(m);
  {
    Problem p = cantilever(q, 0.2);
    const Result lin = solveLinear(p);
    NewtonOptions o;
    o.loadSteps = 1;
    const Result nl = solveNonlinear(p, o);
    const double dl = tipDeflection(q, lin), dn = tipDeflection(q, nl);
    EXPECT_NEAR(dn / dl, 1.0, 1e-3);
    EXPECT_GE(nl.newtonIterations, 2);
  }
  {
    // tip load giving a linear deflection of ~40% of the length: the nonlinear tip moves less
    Problem p = cantilever(q, 0.4 * kL / timoshenko(1.0));
    const Result lin = solveLinear(p);
    NewtonOptions o;
    o.loadSteps = 5;
    const Result nl = solveNonlinear(p, o);
    const double dl = tipDeflection(q, lin), dn = tipDeflection(q, nl);
    std::printf("[nonlinear] large load: linear %.3f mm, nonlinear %.3f mm, %d Newton iterations in %d increments\n", dl, dn,
                nl.newtonIterations, nl.increments);
    EXPECT_LT(dn, 0.97 * dl);
    EXPECT_GT(dn, 0.5 * dl);
    EXPECT_TRUE(nl.u.allFinite());
  }
}

TEST(FeSolver, NoFixedNodesIsAnErrorNotNaN) {
  const TetMesh m = structuredBox(1, 1, 1, 2, 2, 2, 1);
  Problem p;
  p.mesh = &m;
  p.materials = {{1, {1000.0, 0.3}}};
  p.addForce(0, Vector3d(1, 0, 0));
  try {
    solveLinear(p);
    FAIL() << "no exception";
  } catch (const pectus::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("No fixed nodes"), std::string::npos) << e.what();
  }
  // one fixed node: rotations about it remain free
  p.fixNode(0);
  EXPECT_THROW(solveLinear(p), pectus::InputError);
}

TEST(FeSolver, MissingMaterialIsAnError) {
  TetMesh m = structuredBox(1, 1, 1, 1, 1, 1, 2);
  Problem p;
  p.mesh = &m;
  p.materials = {{1, {1000.0, 0.3}}};
  p.fixNode(0);
  EXPECT_THROW({ Solver s(p); }, pectus::InputError);
}

// a TET10 whose corners are fine but whose mid-edge node is moved far off its edge folds inside: refused
// before any solve, naming the tet (its stresses would be NaN); the straight-sided
// mesh solves
TEST(FeSolver, FoldedQuadraticTetIsRefused) {
  TetMesh q = toQuadratic(structuredBox(kB, kB, kL, 1, 1, 2, 1));
  Problem p = cantilever(q, 5.0);
  EXPECT_NO_THROW({ Solver s(p); s.solveLinear(); });
  const int mid = q.tets[0][4];  // the mid-edge node of tet 0's edge (0, 1)
  q.nodes[std::size_t(mid)] += Vector3d(0, 8 * kL, 0);
  try {
    Solver s(p);
    ADD_FAILURE() << "a folded TET10 was accepted";
  } catch (const pectus::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("folds inside"), std::string::npos) << e.what();
  }
}

TEST(FeSolver, NonConvergingNewtonIsAnError) {
  const TetMesh m = structuredBox(kB, kB, kL, 1, 1, 10, 1);
  Problem p = cantilever(m, 50 * kL / timoshenko(1.0));  // absurd load: deflection 50 x length
  NewtonOptions o;
  o.loadSteps = 1;
  o.maxIterations = 3;
  o.maxCutbacks = 1;
  try {
    solveNonlinear(p, o);
    FAIL() << "no exception";
  } catch (const pectus::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("did not converge"), std::string::npos) << e.what();
  }
}

TEST(FeSolver, ThesisMaterials) {
  auto mats = thesisMaterials();
  EXPECT_DOUBLE_EQ(mats.at(1).E, 11500.0);
  EXPECT_DOUBLE_EQ(mats.at(2).E, 12.25);
  EXPECT_DOUBLE_EQ(mats.at(3).E, 11500.0);
  EXPECT_DOUBLE_EQ(mats.at(1).nu, 0.3);
  EXPECT_DOUBLE_EQ(mats.at(2).nu, 0.4);
}

// Hyperelastic materials -------------------------------------------------------------------------
namespace {

// the strain energy of each model as a function of the principal stretches (written from the formula,
// independently of the solver's stress and tangent code)
double energy(MaterialModel model, double E, double nu, double l1, double l2, double l3) {
  const double mu = E / (2 * (1 + nu)), lam = E * nu / ((1 + nu) * (1 - 2 * nu)), K = E / (3 * (1 - 2 * nu));
  const double J = l1 * l2 * l3, I1 = l1 * l1 + l2 * l2 + l3 * l3;
  if (model == MaterialModel::NeoHookean) return mu / 2 * (I1 - 3) - mu * std::log(J) + lam / 2 * std::log(J) * std::log(J);
  return mu / 2 * (std::pow(J, -2.0 / 3.0) * I1 - 3) + K / 2 * (J - 1) * (J - 1);
}
// nominal (first Piola) principal stress dW/dl_i by central differences (error ~1e-10 relative)
double nominal(MaterialModel model, double E, double nu, double l1, double l2, double l3, int i) {
  const double h = 1e-5;
  double a[3] = {l1, l2, l3}, b[3] = {l1, l2, l3};
  a[i] += h, b[i] -= h;
  return (energy(model, E, nu, a[0], a[1], a[2]) - energy(model, E, nu, b[0], b[1], b[2])) / (2 * h);
}
// uniaxial stress at axial stretch l1: the lateral stretch l2 with zero lateral stress (bisection)
double lateralStretch(MaterialModel model, double E, double nu, double l1) {
  double lo = 0.2, hi = 3.0;
  for (int k = 0; k < 200; ++k) {
    const double mid = 0.5 * (lo + hi);
    (nominal(model, E, nu, l1, mid, mid, 1) > 0 ? hi : lo) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

// The material tangent D against central differences of S in E, for every material, on four random
// deformation gradients each (displacement gradients of up to 0.3 per component: stretches and shears
// of ~30 %, J from ~0.5 to ~1.7), with the cartilage's and the bone's constants
namespace {
double materialTangentError(const Material& mat, const Eigen::Matrix3d& F) {
  Eigen::Matrix3d S;
  Eigen::Matrix<double, 6, 6> D, Dn, scratch;
  materialResponse(mat, F, S, D);
  // dS = D dE: perturb E (hence C = I + 2E) in one Voigt component, F = sqrt(C) (S depends on C only)
  const Eigen::Matrix3d C = F.transpose() * F;
  const int I[6] = {0, 1, 2, 0, 1, 0}, J[6] = {0, 1, 2, 1, 2, 2};
  const double h = 1e-6;
  for (int b = 0; b < 6; ++b) {
    Eigen::Matrix3d dE = Eigen::Matrix3d::Zero();
    // engineering shear in Voigt: a unit shear strain component gamma = 2 E_ij
    const double v = b < 3 ? 1.0 : 0.5;
    dE(I[b], J[b]) += v, dE(J[b], I[b]) += b < 3 ? 0.0 : v;
    Eigen::Matrix3d Sp, Sm;
    materialResponse(mat, Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(C + 2 * h * dE).operatorSqrt(), Sp, scratch);
    materialResponse(mat, Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(C - 2 * h * dE).operatorSqrt(), Sm, scratch);
    const Eigen::Matrix3d dS = (Sp - Sm) / (2 * h);
    for (int a = 0; a < 6; ++a) Dn(a, b) = dS(I[a], J[a]);
  }
  EXPECT_TRUE(D.isApprox(D.transpose(), 1e-12)) << materialModelName(mat.model);
  return (Dn - D).norm() / D.norm();
}
}  // namespace

TEST(FeSolver, MaterialTangentIsTheDerivativeOfTheStress) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> d(-0.3, 0.3);
  for (MaterialModel model : {MaterialModel::StVenantKirchhoff, MaterialModel::NeoHookean, MaterialModel::NeoHookeanDecoupled}) {
    for (const Material mat : {Material{12.25, 0.4, model}, Material{11500.0, 0.3, model}}) {
      double worst = 0;
      for (int k = 0; k < 4; ++k) {
        Eigen::Matrix3d F = Eigen::Matrix3d::Identity();
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) F(i, j) += d(rng);
        ASSERT_GT(F.determinant(), 0);
        worst = std::max(worst, materialTangentError(mat, F));
      }
      std::printf("[tangent] %s, E = %g MPa: max |D - dS/dE| / |D| = %.2e over 4 F\n", materialModelName(model), mat.E, worst);
      EXPECT_LT(worst, 1e-7) << materialModelName(model);
    }
  }
}

// Each element's stiffness is the derivative of its internal forces: on one curved TET4 and TET10 (its mid-edge
// nodes moved off the edges) at a large random displacement (strains of ~20 %), every column of Ke
// against central differences of fe, for every material, and the small-strain element (Ke u = fe)
template <int NEN>
double elementTangentError(const TetMesh& m, const Material& mat, bool nonlinear, const Eigen::VectorXd& u) {
  ReferenceTet ref;
  ref.setOrder(m.order);
  const Eigen::Matrix<double, 6, 6> D = linearElasticity(mat);
  Eigen::Matrix<double, 3 * NEN, 3 * NEN> Ke, scratch;
  Eigen::Matrix<double, 3 * NEN, 1> fe, fp, fm;
  tetTangent<NEN>(m, 0, ref, mat, D, u, nonlinear, true, Ke, fe);
  if (!nonlinear) return (Ke * u - fe).norm() / fe.norm();
  Eigen::Matrix<double, 3 * NEN, 3 * NEN> Kn;
  const double h = 1e-6;
  for (int j = 0; j < 3 * NEN; ++j) {
    Eigen::VectorXd up = u, um = u;
    up(j) += h, um(j) -= h;
    tetTangent<NEN>(m, 0, ref, mat, D, up, true, false, scratch, fp);
    tetTangent<NEN>(m, 0, ref, mat, D, um, true, false, scratch, fm);
    Kn.col(j) = (fp - fm) / (2 * h);
  }
  EXPECT_TRUE(Ke.isApprox(Ke.transpose(), 1e-10)) << materialModelName(mat.model) << " TET" << NEN;
  return (Kn - Ke).norm() / Ke.norm();
}

TEST(FeSolver, ElementStiffnessIsTheDerivativeOfTheInternalForces) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> d(-1.0, 1.0);
  TetMesh m4;
  m4.order = 1;
  m4.nodes = {Vector3d(0, 0, 0), Vector3d(2, 0.1, 0), Vector3d(0.3, 1.8, 0.2), Vector3d(0.2, 0.4, 2.1)};
  m4.tets = {{0, 1, 2, 3}};
  m4.tissue = {1};
  TetMesh m10 = toQuadratic(m4);
  for (int n = 4; n < 10; ++n) m10.nodes[n] += 0.05 * Vector3d(d(rng), d(rng), d(rng));  // a curved TET10
  for (const TetMesh* m : {&m4, &m10}) {
    const bool tet10 = m->order == 2;
    for (int state = 0; state < 3; ++state) {  // three deformed states per element
      Eigen::VectorXd u(3 * m->numNodes());
      for (int i = 0; i < u.size(); ++i) u(i) = 0.2 * d(rng);  // displacement gradients of ~0.2
      for (MaterialModel model : {MaterialModel::StVenantKirchhoff, MaterialModel::NeoHookean, MaterialModel::NeoHookeanDecoupled}) {
        const Material mat{12.25, 0.4, model};
        const double err = tet10 ? elementTangentError<10>(*m, mat, true, u) : elementTangentError<4>(*m, mat, true, u);
        std::printf("[element tangent] TET%d %s, state %d: |Ke - dfe/du| / |Ke| = %.2e\n", tet10 ? 10 : 4,
                    materialModelName(model), state, err);
        EXPECT_LT(err, 1e-7) << materialModelName(model) << (tet10 ? " TET10" : " TET4") << " state " << state;
      }
      const Material lin{11500.0, 0.3};
      const double err = tet10 ? elementTangentError<10>(*m, lin, false, u) : elementTangentError<4>(*m, lin, false, u);
      std::printf("[element tangent] TET%d small strain, state %d: |Ke u - fe| / |fe| = %.2e\n", tet10 ? 10 : 4, state, err);
      EXPECT_LT(err, 1e-12);
    }
  }
}

// a 1 x 1 x 2 block stretched or compressed along z by a prescribed top displacement, symmetry planes
// x = 0, y = 0, z = 0, lateral faces free: homogeneous uniaxial stress, which TET4 and TET10 represent exactly
TEST(FeSolver, UniaxialBlockMatchesTheEnergysClosedForm) {
  const double E = 12.25, nu = 0.4, Lz = 2.0;
  double worst = 0;
  for (MaterialModel model : {MaterialModel::NeoHookean, MaterialModel::NeoHookeanDecoupled})
    for (int order : {1, 2})
      for (double strain : {0.5, -0.5}) {
        TetMesh m = structuredBox(1, 1, Lz, 2, 2, 4, 1);
        if (order == 2) m = toQuadratic(m);
        Problem p;
        p.mesh = &m;
        p.materials = {{1, {E, nu, model}}};
        std::vector<int> top;
        int corner = -1;
        for (int i = 0; i < m.numNodes(); ++i) {
          const Vector3d& x = m.nodes[i];
          if (x.x() < 1e-9) p.fixed.push_back({i, 0, 0.0});
          if (x.y() < 1e-9) p.fixed.push_back({i, 1, 0.0});
          if (x.z() < 1e-9) p.fixed.push_back({i, 2, 0.0});
          if (x.z() > Lz - 1e-9) p.fixed.push_back({i, 2, strain * Lz}), top.push_back(i);
          if ((x - Vector3d(1, 1, Lz)).norm() < 1e-9) corner = i;
        }
        ASSERT_GE(corner, 0);
        NewtonOptions o;
        o.loadSteps = order == 2 && strain < 0 ? 20 : 10;
        o.tolResidual = 1e-12;
        o.tolDisplacement = 1e-12;
        const Result r = solveNonlinear(p, o);
        double force = 0;
        for (int i : top) force += r.reactions(3 * i + 2);  // on a 1 x 1 face: the nominal stress
        const double l1 = 1 + strain, l2 = lateralStretch(model, E, nu, l1);
        const double P = nominal(model, E, nu, l1, l2, l2, 0), sigma = P * l1 / (l1 * l2 * l2);  // Cauchy = P l1 / J
        const double errP = std::abs(force / P - 1), errL = std::abs((1 + r.displacement(corner).x()) / l2 - 1);
        double errS = 0;
        for (double vm : r.vonMises) errS = std::max(errS, std::abs(vm / std::abs(sigma) - 1));
        std::printf("[uniaxial] %s TET%d strain %+.0f%%: nominal stress %.6f MPa (closed form %.6f), lateral stretch %.6f "
                    "(%.6f), errors: stress %.1e, lateral %.1e, Cauchy %.1e; %d iterations\n",
                    materialModelName(model), order == 1 ? 4 : 10, 100 * strain, force, P, 1 + r.displacement(corner).x(), l2,
                    errP, errL, errS, r.newtonIterations);
        EXPECT_LT(errP, 1e-6);
        EXPECT_LT(errL, 1e-6);
        EXPECT_LT(errS, 1e-6);
        worst = std::max({worst, errP, errL, errS});
      }
  std::printf("[uniaxial] worst relative error %.1e\n", worst);
}

// the stubby cantilever q (length L along z, clamped at z = 0) under a tip shear traction scaled to a linear
// tip deflection of 40 % of its length
Problem stubbyCantilever(const TetMesh& q, double L, MaterialModel model) {
  Problem p;
  p.mesh = &q;
  p.materials = {{1, {kE, kNu, model}}};
  std::vector<BoundaryFace> tip;
  for (const auto& f : boundaryFaces(q))
    if (q.nodes[f.n[0]].z() > L - 1e-9 && q.nodes[f.n[1]].z() > L - 1e-9 && q.nodes[f.n[2]].z() > L - 1e-9) tip.push_back(f);
  for (int i = 0; i < q.numNodes(); ++i)
    if (q.nodes[i].z() < 1e-9) p.fixNode(i);
  p.force = tractionLoads(q, tip, Vector3d(0, 1.0 / (kB * kB), 0));
  Solver unit(p);
  const double compliance = tipDeflection(q, unit.solveLinear(), L);
  for (auto& f : p.force) f *= 0.4 * L / compliance;
  return p;
}

// Newton on a neo-Hookean stubby cantilever (10 x 10 x 30 mm, TET10, clamped at z = 0, tip shear) at large
// deflection (linear tip deflection 40 % of the length): in every increment the residual falls
// quadratically at the end (rate log(r_k+1 / r_k) / log(r_k / r_k-1) near 2). A stubby beam keeps the
// system's condition number low, so the round-off of the direct solve (condition x 1e-16 relative)
// does not add a linear term to the rate.
TEST(FeSolver, NeoHookeanNewtonConvergesQuadratically) {
  const double L = 30;
  const TetMesh q = toQuadratic(structuredBox(kB, kB, L, 2, 2, 6, 1));
  for (MaterialModel model : {MaterialModel::StVenantKirchhoff, MaterialModel::NeoHookean, MaterialModel::NeoHookeanDecoupled}) {
    const Problem p = stubbyCantilever(q, L, model);
    NewtonOptions o;
    o.loadSteps = 4;
    o.tolResidual = 1e-12;
    o.tolDisplacement = 1e-12;
    o.extrapolate = false;  // each increment from the converged state: the rate from a residual far above the floor
    std::vector<std::vector<double>> rs;
    int reports = 0, withCorrection = 0;
    o.onIteration = [&](const NewtonIteration& it) {
      if (int(rs.size()) <= it.increment) rs.resize(std::size_t(it.increment) + 1);
      rs[std::size_t(it.increment)].push_back(it.residual);
      ++reports;
      withCorrection += std::isfinite(it.correction) && it.correction >= 0;
    };
    const Result r = solveNonlinear(p, o);
    ASSERT_EQ(rs.size(), 4u);
    // one report per iteration: each step taken, and the state that converged (with its check correction)
    EXPECT_EQ(reports, r.newtonIterations + r.increments);
    EXPECT_EQ(withCorrection, reports);
    double worstRate = 10;
    for (const auto& v : rs) {
      std::printf("[quadratic] %s increment residuals:", materialModelName(model));
      for (double x : v) std::printf(" %.3e", x);
      // the rate of the last triple whose residuals are all above 1e-9 of the largest of the increment
      // (>= 1e4 x the round-off floor, ~1e-13 of it, so that the floor does not bend the rate)
      const double above = 1e-9 * *std::max_element(v.begin(), v.end());
      std::size_t k = v.size() - 1;
      while (k >= 2 && v[k] < above) --k;
      ASSERT_GE(k, 2u);
      const double rate = std::log(v[k] / v[k - 1]) / std::log(v[k - 1] / v[k - 2]);
      std::printf(" (rate %.2f at %.1e)\n", rate, v[k]);
      worstRate = std::min(worstRate, rate);
      EXPECT_LE(v.size(), 8u);
    }
    EXPECT_GT(worstRate, 1.7) << materialModelName(model);
    const double d = tipDeflection(q, r, L);
    std::printf("[quadratic] %s: tip %.3f mm (linear %.3f mm), %d iterations\n", materialModelName(model), d, 0.4 * L, r.newtonIterations);
    EXPECT_LT(d, 0.4 * L);
  }
}

// The default convergence criteria against a solve converged to round-off, on the stubby neo-Hookean cantilever
// at a linear tip deflection of 40 % of its length: the displacements agree to 2e-5 (max norm, relative),
// as NewtonOptions states; the predictor (each increment starting from the last increment's path
// extrapolated) saves iterations against starting from the converged state, and ends on the same solution
TEST(FeSolver, DefaultCriteriaAndThePredictor) {
  const double L = 30;
  const TetMesh q = toQuadratic(structuredBox(kB, kB, L, 2, 2, 6, 1));
  const Problem p = stubbyCantilever(q, L, MaterialModel::NeoHookean);
  Solver s(p);
  NewtonOptions tight;
  tight.tolResidual = tight.tolDisplacement = 1e-12;
  NewtonOptions plainStart;
  plainStart.extrapolate = false;
  const Result ref = s.solveNonlinear(tight), byDefault = s.solveNonlinear(NewtonOptions()), plain = s.solveNonlinear(plainStart);
  const double err = (byDefault.u - ref.u).lpNorm<Eigen::Infinity>() / ref.u.lpNorm<Eigen::Infinity>();
  const double errPlain = (plain.u - ref.u).lpNorm<Eigen::Infinity>() / ref.u.lpNorm<Eigen::Infinity>();
  std::printf("[criteria] defaults: %d iterations, error %.1e; without the predictor: %d iterations, error %.1e; "
              "to round-off: %d iterations\n", byDefault.newtonIterations, err, plain.newtonIterations, errPlain,
              ref.newtonIterations);
  EXPECT_LT(err, 2e-5);
  EXPECT_LT(errPlain, 2e-5);
  EXPECT_LT(byDefault.newtonIterations, plain.newtonIterations);
  EXPECT_LT(byDefault.newtonIterations, ref.newtonIterations);
}

// The increments the solve only passes through converge to tolDisplacementBetween, the end and the stops
// to tolDisplacement: the end state is as accurate as with tolDisplacement throughout (2e-5 of a solve
// converged to round-off), in no more iterations, and the stops' states are those of the strict solve
TEST(FeSolver, PassedThroughIncrementsConvergeLooserThanTheEnd) {
  const double L = 30;
  const TetMesh q = toQuadratic(structuredBox(kB, kB, L, 2, 2, 6, 1));
  const Problem p = stubbyCantilever(q, L, MaterialModel::NeoHookean);
  Solver s(p);
  NewtonOptions tight, strict, byDefault;
  tight.tolResidual = tight.tolDisplacement = tight.tolDisplacementBetween = 1e-12;
  strict.tolDisplacementBetween = strict.tolDisplacement;
  strict.stops = byDefault.stops = {0.5};
  std::vector<Eigen::VectorXd> atStop(2);
  strict.onIncrement = [&](double f, const Eigen::VectorXd& u) { if (std::abs(f - 0.5) < 1e-12) atStop[0] = u; };
  byDefault.onIncrement = [&](double f, const Eigen::VectorXd& u) { if (std::abs(f - 0.5) < 1e-12) atStop[1] = u; };
  const Result ref = s.solveNonlinear(tight), a = s.solveNonlinear(strict), b = s.solveNonlinear(byDefault);
  const auto err = [&](const Result& r) { return (r.u - ref.u).lpNorm<Eigen::Infinity>() / ref.u.lpNorm<Eigen::Infinity>(); };
  const double stopDiff = (atStop[1] - atStop[0]).lpNorm<Eigen::Infinity>() / atStop[0].lpNorm<Eigen::Infinity>();
  std::printf("[between] tolDisplacement throughout: %d iterations, error %.1e; between increments %.0e: %d iterations, "
              "error %.1e; the stop's states differ by %.1e\n", a.newtonIterations, err(a), byDefault.tolDisplacementBetween,
              b.newtonIterations, err(b), stopDiff);
  EXPECT_LT(err(a), 2e-5);
  EXPECT_LT(err(b), 2e-5);
  EXPECT_LE(b.newtonIterations, a.newtonIterations);
  EXPECT_LT(stopDiff, 2e-5);
}

// Line search and automatic steps -------------------------------------------------------------------

// a neo-Hookean cantilever loaded in one increment to a linear tip deflection of 1.2 x its length: full
// Newton steps overshoot into inverted elements and the solve gives up; with the line search and the step
// control it follows the path and ends on the solution reached with 20 small increments
TEST(FeSolver, LineSearchAndStepControlFollowAHardPath) {
  const TetMesh q = toQuadratic(structuredBox(kB, kB, kL, 2, 2, 20, 1));
  Problem p = cantilever(q, 1.2 * kL / timoshenko(1.0));
  p.materials.at(1).model = MaterialModel::NeoHookean;
  NewtonOptions plain;
  plain.loadSteps = 1;
  plain.maxCutbacks = 2;
  plain.tolResidual = plain.tolDisplacement = 1e-10;  // both paths to the same solution, far below the defaults' error
  EXPECT_THROW(solveNonlinear(p, plain), NewtonDidNotConverge);
  NewtonOptions robust = plain;
  robust.lineSearch = true;
  robust.adaptiveSteps = true;
  robust.maxCutbacks = 6;
  std::vector<double> factors;
  robust.onIncrement = [&](double f, const Eigen::VectorXd&) { factors.push_back(f); };
  const Result r = solveNonlinear(p, robust);
  NewtonOptions fine = plain;
  fine.loadSteps = 20;
  const Result ref = solveNonlinear(p, fine);
  const double d = tipDeflection(q, r), dref = tipDeflection(q, ref);
  std::printf("[line search] tip %.6f mm (20 increments: %.6f mm), %d increments, %d iterations (20 increments: %d)\n", d, dref,
              r.increments, r.newtonIterations, ref.newtonIterations);
  EXPECT_NEAR(d / dref, 1.0, 1e-7);
  EXPECT_LT(r.newtonIterations, ref.newtonIterations);
  ASSERT_FALSE(factors.empty());
  EXPECT_EQ(factors.back(), 1.0);
  for (std::size_t k = 1; k < factors.size(); ++k) EXPECT_GT(factors[k], factors[k - 1]);
}

// automatic steps grow and shrink the increments but still stop exactly at every requested load factor,
// and the path is the same with one and two threads
TEST(FeSolver, AutomaticStepsHitTheStopsAndAreDeterministic) {
  const TetMesh q = toQuadratic(structuredBox(kB, kB, kL, 2, 2, 20, 1));
  const int grain = minParallelTets();
  setMinParallelTets(1);
  std::vector<std::vector<double>> seen;
  std::vector<Eigen::VectorXd> u;
  for (int threads : {1, 2}) {
    omp_set_num_threads(threads);
    Problem p = cantilever(q, 0.6 * kL / timoshenko(1.0));
    p.materials.at(1).model = MaterialModel::NeoHookeanDecoupled;
    NewtonOptions o;
    o.loadSteps = 3;
    o.lineSearch = true;
    o.adaptiveSteps = true;
    o.targetIterations = 5;
    o.stops = {0.05, 0.1, 0.35, 0.7, 0.71};
    seen.emplace_back();
    o.onIncrement = [&](double f, const Eigen::VectorXd&) { seen.back().push_back(f); };
    u.push_back(solveNonlinear(p, o).u);
  }
  omp_set_num_threads(omp_get_num_procs());
  setMinParallelTets(grain);
  std::printf("[steps] load factors:");
  for (double f : seen[0]) std::printf(" %.4f", f);
  std::printf("\n");
  for (double s : {0.05, 0.1, 0.35, 0.7, 0.71, 1.0})
    EXPECT_NE(std::find(seen[0].begin(), seen[0].end(), s), seen[0].end()) << s;
  EXPECT_EQ(seen[0], seen[1]);
  ASSERT_EQ(u[0].size(), u[1].size());
  EXPECT_EQ(std::memcmp(u[0].data(), u[1].data(), sizeof(double) * std::size_t(u[0].size())), 0);
}

// when Newton fails because an element inverts (full Newton steps under an absurd load), the message
// names it, its tissue and where it is
TEST(FeSolver, FailureNamesTheInvertedElement) {
  const TetMesh m = structuredBox(kB, kB, kL, 1, 1, 10, 1);
  for (MaterialModel model : {MaterialModel::StVenantKirchhoff, MaterialModel::NeoHookean}) {
    Problem p = cantilever(m, 50 * kL / timoshenko(1.0));  // absurd load: deflection 50 x length
    p.materials.at(1).model = model;
    NewtonOptions o;
    o.loadSteps = 1;
    o.maxIterations = model == MaterialModel::StVenantKirchhoff ? 4 : 25;  // until a full step inverts an element
    o.maxCutbacks = 1;
    try {
      solveNonlinear(p, o);
      FAIL() << "no exception";
    } catch (const NewtonDidNotConverge& e) {
      const std::string w = e.what();
      std::printf("[inverted] %s: %s\n", materialModelName(model), w.c_str());
      EXPECT_NE(w.find("inverts"), std::string::npos) << w;
      EXPECT_NE(w.find("tetrahedron "), std::string::npos) << w;
      EXPECT_NE(w.find("of tissue code 1 (bone)"), std::string::npos) << w;
      EXPECT_NE(w.find(") mm"), std::string::npos) << w;
    }
  }
}

// Displacement control ---------------------------------------------------------------------------

// the tip's mean deflection driven to a target: the load factor found, applied as a force (load
// control), gives the same deflection; the constraint holds at every increment
TEST(FeSolver, DisplacementControlFindsTheLoadOfADeflection) {
  const TetMesh q = toQuadratic(structuredBox(kB, kB, kL, 2, 2, 20, 1));
  for (MaterialModel model : {MaterialModel::StVenantKirchhoff, MaterialModel::NeoHookean}) {
    Problem p = cantilever(q, 1.0);  // unit load: the load factor is the force (N)
    p.materials.at(1).model = model;
    Eigen::VectorXd w = Eigen::VectorXd::Zero(3 * q.numNodes());
    int n = 0;
    for (int i = 0; i < q.numNodes(); ++i) n += q.nodes[i].z() > kL - 1e-9;
    for (int i = 0; i < q.numNodes(); ++i)
      if (q.nodes[i].z() > kL - 1e-9) w(3 * i + 1) = 1.0 / n;
    const double target = 0.4 * kL;
    Solver s(p);
    NewtonOptions o;
    o.loadSteps = 5;
    o.tolResidual = o.tolDisplacement = 1e-10;  // the two solves agree far below the defaults' error
    std::vector<std::pair<double, double>> path;
    o.onIncrement = [&](double L, const Eigen::VectorXd& u) { path.emplace_back(L, w.dot(u)); };
    const Result r = s.solveControlled(w, target, o);
    ASSERT_EQ(path.size(), 5u);
    for (std::size_t k = 0; k < path.size(); ++k) EXPECT_NEAR(path[k].second, target * double(k + 1) / 5, 1e-6 * target);
    for (std::size_t k = 1; k < path.size(); ++k) EXPECT_GT(path[k].first, path[k - 1].first);  // stiffening: force rises
    NewtonOptions lc;
    lc.loadSteps = 5;
    lc.tolResidual = lc.tolDisplacement = 1e-10;
    const Result byForce = s.solveNonlinear(lc, r.loadFactor);
    const double d = tipDeflection(q, r), dForce = tipDeflection(q, byForce);
    std::printf("[control] %s: target %.3f mm -> load %.4f N, deflection %.6f; that load as a force: %.6f mm; iterations %d / %d\n",
                materialModelName(model), target, r.loadFactor, d, dForce, r.newtonIterations, byForce.newtonIterations);
    EXPECT_NEAR(d, target, 1e-6 * target);
    EXPECT_NEAR(dForce / target, 1.0, 1e-6);
    EXPECT_GT(r.loadFactor, target / timoshenko(1.0));  // more than the linear estimate (the beam stiffens)
  }
}

TEST(FeSolver, DisplacementControlRefusesPrescribedDisplacements) {
  const TetMesh m = structuredBox(kB, kB, kL, 1, 1, 4, 1);
  Problem p = cantilever(m, 1.0);
  p.fixed.push_back({m.numNodes() - 1, 0, 0.5});
  Solver s(p);
  Eigen::VectorXd w = Eigen::VectorXd::Zero(3 * m.numNodes());
  w(3 * (m.numNodes() - 1) + 1) = 1;
  try {
    s.solveControlled(w, 1.0);
    FAIL() << "no exception";
  } catch (const pectus::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("zero prescribed displacements"), std::string::npos) << e.what();
  }
  EXPECT_THROW(s.solveControlled(Eigen::VectorXd::Zero(3), 1.0), pectus::InputError);
}

// OpenBLAS's threads spin for about 0.1 s of CPU after they start and after each threaded call; after
// restBlasThreads the process takes no CPU while it waits, and the BLAS still multiplies right (it starts
// its threads again). With a BLAS without threads both hold as well.
TEST(FeSolver, RestingTheBlasThreadsStopsTheirSpin) {
  using Dgemm = void (*)(const char*, const char*, const int*, const int*, const int*, const double*, const double*,
                         const int*, const double*, const int*, const double*, double*, const int*);
  const auto dgemm = reinterpret_cast<Dgemm>(dlsym(RTLD_DEFAULT, "dgemm_"));  // CHOLMOD's BLAS
  ASSERT_NE(dgemm, nullptr);
  const int n = 400;
  std::vector<double> a(std::size_t(n * n), 1.0), b(std::size_t(n * n), 2.0), c(std::size_t(n * n), 0.0);
  const double one = 1, zero = 0;
  auto product = [&] { dgemm("N", "N", &n, &n, &n, &one, a.data(), &n, b.data(), &n, &zero, c.data(), &n); };
  auto cpuWhileWaiting = [] {
    auto seconds = [] {
      rusage r{};
      getrusage(RUSAGE_SELF, &r);
      return double(r.ru_utime.tv_sec + r.ru_stime.tv_sec) + 1e-6 * double(r.ru_utime.tv_usec + r.ru_stime.tv_usec);
    };
    const double before = seconds();
    usleep(300000);
    return seconds() - before;
  };
  product();
  restBlasThreads();
  EXPECT_LT(cpuWhileWaiting(), 0.02);
  std::fill(c.begin(), c.end(), 0.0);
  product();
  EXPECT_EQ(c.front(), 2.0 * n);
  EXPECT_EQ(c.back(), 2.0 * n);
}
