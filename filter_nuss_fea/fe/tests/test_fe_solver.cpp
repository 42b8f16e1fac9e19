// Verification of the pectus_fe solvers: patch tests, cantilever vs beam theory, Lame cylinder,
// nonlinear vs linear, singular systems and non-converging Newton solves.
#include <gtest/gtest.h>

#include <omp.h>

#include <cmath>
#include <cstring>
#include <random>

#include "pectus/errors.h"
#include "pectus/fe/solver.h"

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

double tipDeflection(const TetMesh& m, const Result& r) {
  double s = 0;
  int n = 0;
  for (int i = 0; i < m.numNodes(); ++i)
    if (m.nodes[i].z() > kL - 1e-9) s += r.displacement(i).y(), ++n;
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
