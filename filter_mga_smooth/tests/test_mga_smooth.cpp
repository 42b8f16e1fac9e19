// MGA surface mesh smoothing (thesis ch. 4.2): planar grid, saddle, quads, fixed nodes, determinism.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <random>

#include "pectus/smooth/mga_smooth.h"
#include "pectus/folds.h"
#include "pectus/c1/surface.h"
#include "pectus/surface_cmesh.h"
#include "pectus/errors.h"

using pectus::Vec3;
using pectus::c1::TriMesh;
namespace sm = pectus::smooth;

namespace {

/// n x n grid on [0, n-1]^2 (z = 0), interior jittered in the plane by +-jitter; diagonals a-c
TriMesh grid(int n, double jitter, unsigned seed, std::vector<std::array<int, 4>>* quads = nullptr) {
  TriMesh t;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-jitter, jitter);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      Vec3 p(i, j, 0);
      if (i > 0 && j > 0 && i < n - 1 && j < n - 1) {
        // drawn in a fixed order (y first, as gcc evaluates Vec3(u(rng), u(rng), 0)): the order of function
        // arguments is unspecified and clang's differs, so drawing in the arguments gives the TSan build
        // another grid
        const double dy = u(rng), dx = u(rng);
        p += Vec3(dx, dy, 0);
      }
      t.V.push_back(p);
    }
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const int a = j * n + i, b = a + 1, c = a + n + 1, d = a + n;
      t.F.push_back({a, b, c});
      t.F.push_back({a, c, d});
      if (quads) quads->push_back({a, b, c, d});
    }
  return t;
}

std::unique_ptr<CMeshO> toMesh(const TriMesh& t, bool quads = false) {
  auto m = std::make_unique<CMeshO>();
  pectus::toMesh(t, *m);
  if (quads)
    for (std::size_t f = 0; f + 1 < m->face.size(); f += 2) {
      m->face[f].SetF(2);      // (a b c): edge c-a
      m->face[f + 1].SetF(0);  // (a c d): edge a-c
    }
  return m;
}

double saddle(double x, double y) { return x * x / 10 - y * y / 4; }

/// the saddle z = x^2/10 - y^2/4 on [-5,5]^2: a lattice of rows with alternating offsets (about 600
/// nodes, near-equilateral in the plane), interior nodes jittered in the plane by +-0.3 h
TriMesh saddleMesh(unsigned seed) {
  const int nx = 23, ny = 26;
  const double h = 10.0 / (nx - 1);
  TriMesh t;
  std::vector<std::vector<int>> rows(ny);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.3 * h, 0.3 * h);
  for (int j = 0; j < ny; ++j) {
    const double y = -5 + 10.0 * j / (ny - 1);
    std::vector<double> xs;
    if (j % 2 == 0) {
      for (int i = 0; i < nx; ++i) xs.push_back(-5 + h * i);
    } else {
      xs.push_back(-5);
      for (int i = 0; i + 1 < nx; ++i) xs.push_back(-5 + h * (i + 0.5));
      xs.push_back(5);
    }
    for (std::size_t i = 0; i < xs.size(); ++i) {
      double x = xs[i], yy = y;
      const bool interior = j > 0 && j < ny - 1 && i > 0 && i + 1 < xs.size();
      if (interior) { x += u(rng); yy += u(rng); }
      rows[std::size_t(j)].push_back(int(t.V.size()));
      t.V.emplace_back(x, yy, saddle(x, yy));
    }
  }
  for (int j = 0; j + 1 < ny; ++j) {
    const auto& A = rows[std::size_t(j)];
    const auto& B = rows[std::size_t(j + 1)];
    std::size_t i = 0, k = 0;
    while (i + 1 < A.size() || k + 1 < B.size()) {
      const bool advA = k + 1 >= B.size() ||
                        (i + 1 < A.size() && t.V[std::size_t(A[i + 1])].x() < t.V[std::size_t(B[k + 1])].x());
      if (advA) { t.F.push_back({A[i], A[i + 1], B[k]}); ++i; }
      else { t.F.push_back({A[i], B[k + 1], B[k]}); ++k; }
    }
  }
  return t;
}

std::vector<Vec3> positions(const CMeshO& m) {
  std::vector<Vec3> p;
  for (const auto& v : m.vert) p.emplace_back(v.cP()[0], v.cP()[1], v.cP()[2]);
  return p;
}

sm::Options fastOptions() {
  sm::Options o;
  o.maxSweeps = 8;
  o.generations = 16;
  o.restarts = 3;
  o.seed = 7;
  return o;
}

}  // namespace

TEST(MgaSmooth, PlanarGridImprovesKeepsBoundaryAndPlane) {
  const TriMesh t = grid(12, 0.35, 1);
  const auto mp = toMesh(t);
  const CMeshO& m = *mp;
  const auto r = sm::smoothMesh(m, fastOptions());
  std::printf("planar grid: alpha mean %.4f -> %.4f, min %.4f -> %.4f, %zu moved, %d sweeps, %.2f s\n",
              r.before.mean, r.after.mean, r.before.min, r.after.min, r.nodesMoved, r.sweeps, r.seconds);
  EXPECT_GT(r.after.mean, r.before.mean + 0.02);
  EXPECT_GT(r.after.min, r.before.min + 0.05);
  EXPECT_EQ(r.boundaryNodes, 44u);
  EXPECT_EQ(r.freeNodes, 100u);
  EXPECT_GT(r.nodesMoved, 50u);
  for (int j = 0; j < 12; ++j)
    for (int i = 0; i < 12; ++i) {
      const int v = j * 12 + i;
      EXPECT_LT(std::abs(r.positions[std::size_t(v)].z()), 1e-9);
      if (i == 0 || j == 0 || i == 11 || j == 11) EXPECT_EQ(r.positions[std::size_t(v)], t.V[std::size_t(v)]);
    }
  ASSERT_EQ(r.perFace.size(), m.face.size());
  double mean = 0;
  for (double q : r.perFace) mean += q;
  EXPECT_NEAR(mean / double(r.perFace.size()), r.after.mean, 1e-9);
}

TEST(MgaSmooth, SaddleTriangles) {
  const TriMesh t = saddleMesh(3);
  ASSERT_GT(t.V.size(), 550u);
  ASSERT_LT(t.V.size(), 700u);
  const auto mp = toMesh(t);
  const CMeshO& m = *mp;
  sm::Options o;
  o.maxSweeps = 15;
  o.tolerance = 1e-4;
  o.seed = 11;
  const auto r = sm::smoothMesh(m, o);
  double dev = 0;
  for (const auto& p : r.positions) dev = std::max(dev, std::abs(p.z() - saddle(p.x(), p.y())));
  std::printf("saddle (%zu nodes, %zu triangles): alpha mean %.4f -> %.4f, min %.4f -> %.4f, %zu moved, "
              "%d sweeps, %d colours, max |z - saddle| %.5f, %.2f s\n",
              t.V.size(), t.F.size(), r.before.mean, r.after.mean, r.before.min, r.after.min, r.nodesMoved, r.sweeps,
              r.colours, dev, r.seconds);
  EXPECT_GT(r.after.mean, 0.85);  // measured 0.853 (seed 11, 15 sweeps, guard 0.7)
  EXPECT_GT(r.after.min, r.before.min);
  // the bound of this mesh is 0.3133, two corner triangles whose three nodes are boundary nodes (a minimum
  // of 0.40 cannot be reached while the boundary stays fixed; bench/saddle_bound.py); the search is
  // stochastic: 0.2868 with seed 11 (xoshiro256**), the bound with a std::mt19937_64 stream
  EXPECT_GT(r.after.min, 0.28);
  EXPECT_LT(dev, 0.01);
}

TEST(MgaSmooth, QuadGrid) {
  std::vector<std::array<int, 4>> quads;
  const TriMesh t = grid(10, 0.3, 5, &quads);
  const auto mp = toMesh(t, true);
  const CMeshO& m = *mp;
  for (auto method : {sm::Method::MicroGA, sm::Method::ConjugateGradient}) {
    sm::Options o = fastOptions();
    o.kind = pectus::ElementKind::Quads;
    o.method = method;
    const auto r = sm::smoothMesh(m, o);
    std::printf("quad grid (%s): beta mean %.4f -> %.4f, min %.4f -> %.4f, %zu moved, %.2f s\n",
                method == sm::Method::MicroGA ? "MGA" : "CG", r.before.mean, r.after.mean, r.before.min, r.after.min,
                r.nodesMoved, r.seconds);
    EXPECT_EQ(r.quads, 81u);
    EXPECT_EQ(r.elements, 81u);
    EXPECT_GT(r.after.mean, 0.99);  // the ideal is a square grid (beta 1)
    EXPECT_GT(r.after.min, r.before.min + 0.2);
    // both triangles of a quad carry its beta
    for (std::size_t f = 0; f + 1 < r.perFace.size(); f += 2) EXPECT_EQ(r.perFace[f], r.perFace[f + 1]);
    for (int j = 0; j < 10; ++j)
      for (int i = 0; i < 10; ++i) {
        const auto v = std::size_t(j * 10 + i);
        EXPECT_LT(std::abs(r.positions[v].z()), 1e-9);
        if (i == 0 || j == 0 || i == 9 || j == 9) EXPECT_EQ(r.positions[v], t.V[v]);
      }
  }
}

TEST(MgaSmooth, SameResultForOneAndTwoThreads) {
  const auto mp = toMesh(saddleMesh(4));
  const CMeshO& m = *mp;
  sm::Options o = fastOptions();
  o.maxSweeps = 3;
  o.tolerance = 0;
  omp_set_num_threads(1);
  const auto r1 = sm::smoothMesh(m, o);
  omp_set_num_threads(2);
  const auto r2 = sm::smoothMesh(m, o);
  ASSERT_EQ(r1.positions.size(), r2.positions.size());
  std::size_t differ = 0;
  for (std::size_t i = 0; i < r1.positions.size(); ++i) differ += r1.positions[i] != r2.positions[i];
  EXPECT_EQ(differ, 0u);
  EXPECT_GT(r1.nodesMoved, 100u);
  // the guided searches too (their per-thread buffers: the star, the fan, the micro-GA workspace)
  for (const auto mode : {sm::ElementSearch::Guided, sm::ElementSearch::GuidedLocal}) {
    sm::Options g = o;
    g.elementSearch = mode;
    omp_set_num_threads(1);
    const auto g1 = sm::smoothMesh(m, g);
    omp_set_num_threads(2);
    const auto g2 = sm::smoothMesh(m, g);
    std::size_t gd = 0;
    for (std::size_t i = 0; i < g1.positions.size(); ++i) gd += g1.positions[i] != g2.positions[i];
    EXPECT_EQ(gd, 0u);
    EXPECT_EQ(g1.evaluations, g2.evaluations);
    EXPECT_GT(g1.nodesMoved, 100u);
  }
  // another seed gives another (also improving) result: the seed is used
  o.seed = 8;
  const auto r3 = sm::smoothMesh(m, o);
  std::size_t differ3 = 0;
  for (std::size_t i = 0; i < r1.positions.size(); ++i) differ3 += r1.positions[i] != r3.positions[i];
  EXPECT_GT(differ3, 0u);
}

// the guided element searches (Options::elementSearch) do a fraction of the thesis' work for nearly its
// quality, on triangles and on quads, and keep the no-fold rule; the local one does less than the guided
TEST(MgaSmooth, GuidedElementSearch) {
  std::vector<std::array<int, 4>> quads;
  const TriMesh q = grid(10, 0.3, 5, &quads);
  const auto meshes = {std::make_pair(toMesh(saddleMesh(3)), false), std::make_pair(toMesh(q, true), true)};
  for (const auto& [mp, isQuads] : meshes) {
    sm::Options o = fastOptions();
    o.kind = isQuads ? pectus::ElementKind::Quads : pectus::ElementKind::Triangles;
    const auto all = sm::smoothMesh(*mp, o);
    o.elementSearch = sm::ElementSearch::Guided;
    const auto guided = sm::smoothMesh(*mp, o);
    o.elementSearch = sm::ElementSearch::GuidedLocal;
    const auto local = sm::smoothMesh(*mp, o);
    std::printf("%s: every element mean %.4f min %.4f, %zu evaluations; guided mean %.4f min %.4f, %zu evaluations; "
                "local mean %.4f min %.4f, %zu evaluations\n",
                isQuads ? "quad grid" : "saddle", all.after.mean, all.after.min, all.evaluations, guided.after.mean,
                guided.after.min, guided.evaluations, local.after.mean, local.after.min, local.evaluations);
    EXPECT_LT(double(guided.evaluations), 0.6 * double(all.evaluations));
    EXPECT_LT(local.evaluations, guided.evaluations);
    // the local search gives up nodes whose first element does not gain: on this jittered saddle it ends
    // 0.014 below (measured 0.8498 against 0.8638)
    EXPECT_GT(guided.after.mean, all.after.mean - 0.003);
    EXPECT_GT(local.after.mean, all.after.mean - 0.02);
    for (const auto* r : {&guided, &local}) {
      EXPECT_GT(r->after.mean, r->before.mean + 0.05);
      EXPECT_GE(r->after.min, r->before.min);
      EXPECT_EQ(r->foldedAfter, 0u);
    }
  }
}

TEST(MgaSmooth, UserFixedAndFeatureNodesStay) {
  // a grid folded by 90 degrees along the line x = 5: the crease nodes are feature nodes
  TriMesh t = grid(11, 0.3, 9);
  for (int j = 0; j < 11; ++j) t.V[std::size_t(j * 11 + 5)].x() = 5;  // a straight crease line
  for (auto& p : t.V)
    if (p.x() > 5) p = Vec3(5, p.y(), p.x() - 5);
  const auto mp = toMesh(t);
  const CMeshO& m = *mp;
  std::vector<char> fixedSel(m.vert.size(), 0);
  fixedSel[2 * 11 + 2] = 1;
  fixedSel[3 * 11 + 3] = 1;
  const auto r = sm::smoothMesh(m, fastOptions(), fixedSel);
  const auto in = positions(m);  // the mesh stores floats
  EXPECT_EQ(r.userFixedNodes, 2u);
  EXPECT_EQ(r.featureNodes, 9u);  // the interior crease nodes
  EXPECT_EQ(r.positions[2 * 11 + 2], in[2 * 11 + 2]);
  EXPECT_EQ(r.positions[3 * 11 + 3], in[3 * 11 + 3]);
  for (std::size_t i = 0; i < t.V.size(); ++i)
    if (std::abs(t.V[i].x() - 5) < 1e-12 && t.V[i].z() == 0) EXPECT_EQ(r.positions[i], in[i]) << i;
  EXPECT_GT(r.after.mean, r.before.mean);

  // the same by the feature angle (60 degrees); at 180 degrees: no feature node
  sm::Options o = fastOptions();
  o.features = sm::FeatureDetection::Angles;
  EXPECT_EQ(sm::smoothMesh(m, o).featureNodes, 9u);
  o.featureAngleDeg = 180;
  EXPECT_EQ(sm::smoothMesh(m, o).featureNodes, 0u);
}

TEST(MgaSmooth, NeverFoldsAVeryBadMesh) {
  // heavy jitter: the search must never invert an element
  const TriMesh t = grid(9, 0.4, 13);
  for (const auto& f : t.F)  // a valid (unfolded) start
    ASSERT_GT((t.V[std::size_t(f[1])] - t.V[std::size_t(f[0])]).cross(t.V[std::size_t(f[2])] - t.V[std::size_t(f[0])]).z(), 0);
  const auto mp = toMesh(t);
  const CMeshO& m = *mp;
  const auto r = sm::smoothMesh(m, fastOptions());
  for (const auto& f : t.F) {
    const Vec3 a = r.positions[std::size_t(f[0])], b = r.positions[std::size_t(f[1])], c = r.positions[std::size_t(f[2])];
    EXPECT_GT((b - a).cross(c - a).z(), 0);
  }
  EXPECT_GE(r.after.min, r.before.min);
  // the same, counted by the core against the surface normal at every node of every element
  EXPECT_EQ(r.foldedBefore, 0u);
  EXPECT_EQ(r.foldedAfter, 0u);
}

TEST(MgaSmooth, FoldedElementsNeverIncrease) {
  // a rough surface (heights jittered by about one edge length): many elements start folded against the
  // C1 normal at one of their nodes. A move is tested against the normals of all nodes of its elements,
  // so no sweep can fold a neighbour's element: the count falls with every sweep budget, both methods.
  TriMesh t = grid(12, 0.3, 21);
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-0.8, 0.8);
  for (auto& p : t.V) p.z() = u(rng);
  const auto mp = toMesh(t);
  for (auto method : {sm::Method::MicroGA, sm::Method::ConjugateGradient}) {
    sm::Options o = fastOptions();
    o.method = method;
    o.featureAngleDeg = o.singularAngleDeg = 180;
    o.worstGuard = 0;
    std::size_t last = 0;
    for (int sweeps : {1, 2, 4}) {
      o.maxSweeps = sweeps;
      o.tolerance = 0;
      const auto r = sm::smoothMesh(*mp, o);
      std::printf("rough grid (%s, %d sweeps): folded %zu -> %zu, alpha mean %.4f -> %.4f\n",
                  method == sm::Method::MicroGA ? "MGA" : "CG", sweeps, r.foldedBefore, r.foldedAfter, r.before.mean,
                  r.after.mean);
      EXPECT_GT(r.foldedBefore, 10u);
      EXPECT_LT(r.foldedAfter, r.foldedBefore);
      if (sweeps > 1) EXPECT_LE(r.foldedAfter, last);
      last = r.foldedAfter;
    }
  }
}

TEST(MgaSmooth, NoNewFoldsOnAFoldedSurface) {
  // a gently curved grid with every 11th node (of the interior) pushed 1.6 times the way to its right-hand neighbour,
  // past it: the triangles there face against their edge neighbours (folds, pectus/folds.h). Neither method
  // may fold an element that was not folded, and the folds, counted again here from the result, may only fall
  TriMesh t = grid(16, 0.25, 5);
  for (auto& p : t.V) p.z() = 0.02 * ((p.x() - 7.5) * (p.x() - 7.5) + (p.y() - 7.5) * (p.y() - 7.5));
  for (int v = 18; v < int(t.V.size()); v += 11)
    if (v % 16 > 0 && v % 16 < 14 && v / 16 > 0 && v / 16 < 15) t.V[std::size_t(v)] += 1.6 * (t.V[std::size_t(v + 1)] - t.V[std::size_t(v)]);
  std::vector<pectus::Element> E;
  for (const auto& f : t.F) {
    pectus::Element e;
    e.v = {f[0], f[1], f[2], -1};
    E.push_back(e);
  }
  const pectus::Folds folds(E, t.V.size());
  const std::vector<char> in = folds.all(t.V);
  const std::size_t nIn = std::size_t(std::count(in.begin(), in.end(), char(1)));
  ASSERT_GE(nIn, 10u);
  const auto mp = toMesh(t);
  for (auto method : {sm::Method::MicroGA, sm::Method::ConjugateGradient}) {
    sm::Options o = fastOptions();
    o.method = method;
    const auto r = sm::smoothMesh(*mp, o);
    const std::vector<char> out = folds.all(r.positions);
    std::size_t nOut = 0, nNew = 0;
    for (std::size_t e = 0; e < in.size(); ++e) nOut += out[e], nNew += out[e] && !in[e];
    std::printf("folded grid (%s): folds %zu -> %zu, %zu new, %zu moves undone; alpha mean %.4f -> %.4f\n",
                method == sm::Method::MicroGA ? "MGA" : "CG", nIn, nOut, nNew,
                r.movesUndoneForFolds + r.nodesPutBackFolds, r.before.mean, r.after.mean);
    EXPECT_EQ(nNew, 0u);
    EXPECT_LT(nOut, nIn);
    EXPECT_EQ(r.foldsBefore, nIn);
    EXPECT_EQ(r.foldsAfter, nOut);
    EXPECT_EQ(r.foldsNew, 0u);
    EXPECT_GT(r.after.mean, r.before.mean);
  }
}

TEST(MgaSmooth, GuardHoldsForAFoldedStar) {
  // the input of tests/fuzz/corpus/mga/guard-folded-bipyramid: a jittered triangular bipyramid whose ring
  // node 3 starts with two faces folded against the C1 surface normal there; a search whose invalid stars
  // ignore the guard trades one fold for a face of alpha 1.5e-5, below the guard
  TriMesh t;
  t.V = {{0, 0, -0.81244373235675593},
         {0.87372298579091856, -0.21003524895910325, 0.35645207301319376},
         {-0.25778572278177087, 0.86084445914148167, 0.35645207301319376},
         {0.073600970919801029, -0.89559452811212104, 0.35645207301319376},
         {0, 0, 0.81244373235675593}};
  t.F = {{0, 2, 1}, {0, 3, 2}, {0, 1, 3}, {4, 1, 2}, {4, 2, 3}, {4, 3, 1}};
  const auto mp = toMesh(t);
  sm::Options o;
  o.maxSweeps = 2;
  o.generations = 3;
  o.restarts = 0;
  o.population = 3;
  o.featureAngleDeg = o.singularAngleDeg = 177.88235294117646;  // no fixed node
  o.worstGuard = 0.0012054627298390174;
  o.cgIterations = 1;
  o.seed = 0;
  for (const auto method : {sm::Method::ConjugateGradient, sm::Method::MicroGA})
    for (const double guard : {o.worstGuard, 0.35}) {
      o.method = method;
      o.worstGuard = guard;
      const auto r = sm::smoothMesh(*mp, o);
      EXPECT_GE(r.after.min, std::min(r.before.min, guard))
          << (method == sm::Method::MicroGA ? "MGA" : "CG") << ", guard " << guard;
    }
}

double maxSaddleDeviation(const std::vector<Vec3>& P) {
  double dev = 0;
  for (const auto& p : P) dev = std::max(dev, std::abs(p.z() - saddle(p.x(), p.y())));
  return dev;
}

TEST(GradientSmooth, SaddleTrianglesVersusMga) {
  // the thesis' Table 4-1 comparison on one input: both improve, CG needs fewer fitness evaluations
  const auto mp = toMesh(saddleMesh(3));
  const CMeshO& m = *mp;
  sm::Options o;
  o.maxSweeps = 15;
  o.seed = 11;
  o.method = sm::Method::ConjugateGradient;
  const auto cg = sm::smoothMesh(m, o);
  o.method = sm::Method::MicroGA;
  o.maxSweeps = 3;
  const auto ga = sm::smoothMesh(m, o);
  const double dev = maxSaddleDeviation(cg.positions);
  std::printf("saddle CG: alpha mean %.4f -> %.4f, min %.4f -> %.4f, %zu moved, %d sweeps, %zu evaluations "
              "(MGA, 3 sweeps: %zu), max |z - saddle| %.5f, %.2f s\n",
              cg.before.mean, cg.after.mean, cg.before.min, cg.after.min, cg.nodesMoved, cg.sweeps, cg.evaluations,
              ga.evaluations, dev, cg.seconds);
  EXPECT_GT(cg.after.mean, 0.84);
  EXPECT_GT(cg.after.min, cg.before.min);
  EXPECT_GT(cg.after.min, 0.2);
  EXPECT_LT(dev, 0.01);
  EXPECT_GT(cg.nodesMoved, 400u);
  EXPECT_LT(cg.evaluations * 3, ga.evaluations * std::size_t(cg.sweeps));  // per sweep, under a third
}

TEST(GradientSmooth, GuardAndFinalWorstElementPass) {
  // the guard trades mean for minimum; the final pass lifts the minimum to the bound of this mesh, the
  // triangles whose three nodes are all boundary nodes (alpha 0.3133; printed by bench/saddle_bound.py)
  const auto mp = toMesh(saddleMesh(3));
  const CMeshO& m = *mp;
  sm::Options o;
  o.method = sm::Method::ConjugateGradient;
  o.maxSweeps = 30;
  o.worstGuard = 0;  // the thesis' plain sum
  const auto plain = sm::smoothMesh(m, o);
  o.worstGuard = 0.3;
  o.minPassBelow = 0.32;
  const auto pass = sm::smoothMesh(m, o);
  std::printf("saddle CG: plain sum mean %.4f min %.4f; guard 0.3 + final pass below 0.32: mean %.4f min %.4f "
              "(%d + %d sweeps)\n", plain.after.mean, plain.after.min, pass.after.mean, pass.after.min, pass.sweeps,
              pass.minPassSweeps);
  EXPECT_GT(plain.after.mean, 0.875);
  EXPECT_LT(plain.after.min, 0.1);  // the plain sum sacrifices single elements
  EXPECT_GT(pass.minPassSweeps, 0);
  EXPECT_GT(pass.after.min, 0.313);
  EXPECT_GT(pass.after.mean, 0.865);
  o.minPassBelow = 1.5;
  EXPECT_THROW(sm::smoothMesh(m, o), pectus::InputError);
  o.minPassBelow = 0;
  o.worstGuard = -0.1;
  EXPECT_THROW(sm::smoothMesh(m, o), pectus::InputError);
}

TEST(GradientSmooth, QuadSaddleTarget) {
  // the quad target (mean beta >= 0.85, min >= 0.40) on a jittered 25 x 25 quad grid on the saddle,
  // with guard 0.4 and the final worst-element pass below 0.45 (bench/mga_smooth.py has the same row)
  std::vector<std::array<int, 4>> quads;
  TriMesh t = grid(25, 0.3, 5, &quads);
  for (auto& p : t.V) {
    p.x() = -5 + 10 * p.x() / 24;
    p.y() = -5 + 10 * p.y() / 24;
    p.z() = saddle(p.x(), p.y());
  }
  const auto mp = toMesh(t, true);
  sm::Options o;
  o.kind = pectus::ElementKind::Quads;
  o.method = sm::Method::ConjugateGradient;
  o.worstGuard = 0.4;
  o.minPassBelow = 0.45;
  const auto r = sm::smoothMesh(*mp, o);
  const double dev = maxSaddleDeviation(r.positions);
  std::printf("quad saddle CG: beta mean %.4f -> %.4f, min %.4f -> %.4f, max |z - saddle| %.5f, %d + %d sweeps\n",
              r.before.mean, r.after.mean, r.before.min, r.after.min, dev, r.sweeps, r.minPassSweeps);
  EXPECT_EQ(r.quads, 576u);
  EXPECT_GE(r.after.mean, 0.85);
  EXPECT_GE(r.after.min, 0.40);
  EXPECT_LT(dev, 0.004);
}

TEST(GradientSmooth, NeverFoldsAndIsThreadIndependent) {
  const TriMesh t = grid(9, 0.4, 13);
  const auto mp = toMesh(t);
  const CMeshO& m = *mp;
  sm::Options o = fastOptions();
  o.method = sm::Method::ConjugateGradient;
  omp_set_num_threads(1);
  const auto r1 = sm::smoothMesh(m, o);
  omp_set_num_threads(2);
  const auto r = sm::smoothMesh(m, o);
  for (const auto& f : t.F) {
    const Vec3 a = r.positions[std::size_t(f[0])], b = r.positions[std::size_t(f[1])], c = r.positions[std::size_t(f[2])];
    EXPECT_GT((b - a).cross(c - a).z(), 0);
  }
  EXPECT_GT(r.after.min, r.before.min + 0.1);
  std::size_t differ = 0;
  for (std::size_t i = 0; i < r.positions.size(); ++i) differ += r.positions[i] != r1.positions[i];
  EXPECT_EQ(differ, 0u);
}

/// a cone (apex height `height` over a ring of 9 nodes at radius 1, jittered in angle) on a flat
/// annulus out to radius 2 (boundary): the apex is the only node with a wide normal cone
TriMesh cone(double height) {
  TriMesh t;
  t.V.emplace_back(0.1, -0.05, height);
  const int n = 9;
  for (int ring = 1; ring <= 2; ++ring)
    for (int i = 0; i < n; ++i) {
      const double a = 2 * M_PI * (i + (ring == 1 ? 0.25 * std::sin(3.0 * i) : 0.5)) / n;
      t.V.emplace_back(ring * std::cos(a), ring * std::sin(a), 0);
    }
  for (int i = 0; i < n; ++i) {
    const int a = 1 + i, b = 1 + (i + 1) % n, A = 1 + n + i, B = 1 + n + (i + 1) % n;
    t.F.push_back({0, a, b});
    t.F.push_back({a, A, b});
    t.F.push_back({b, A, B});
  }
  return t;
}

TEST(MgaSmooth, SingularNodesStay) {
  const TriMesh t = cone(0.6);  // faces around the apex tilt by about 31 degrees: normal cone about 62
  const auto mp = toMesh(t);
  const CMeshO& m = *mp;
  const auto in = positions(m);
  for (auto method : {sm::Method::MicroGA, sm::Method::ConjugateGradient}) {
    sm::Options o = fastOptions();
    o.method = method;
    o.features = sm::FeatureDetection::Angles;
    o.singularAngleDeg = 50;
    const auto r = sm::smoothMesh(m, o);
    EXPECT_EQ(r.singularNodes, 1u);
    EXPECT_EQ(r.featureNodes, 0u);
    EXPECT_EQ(r.boundaryNodes, 9u);
    EXPECT_EQ(r.freeNodes, 9u);
    EXPECT_EQ(r.positions[0], in[0]);
    // with the singular test off the apex is free and moves
    o.singularAngleDeg = 180;
    const auto r2 = sm::smoothMesh(m, o);
    EXPECT_EQ(r2.singularNodes, 0u);
    EXPECT_EQ(r2.freeNodes, 10u);
    EXPECT_GT((r2.positions[0] - in[0]).norm(), 1e-3);
    // the default singular angle (90 degrees) keeps this gentle cone free, and fixes a steep one (normal
    // cone ~ 127)
    sm::Options a = fastOptions();
    a.features = sm::FeatureDetection::Angles;
    EXPECT_EQ(sm::smoothMesh(m, a).singularNodes, 0u);
    const auto steep = toMesh(cone(2.0));
    sm::Options d = a;
    d.featureAngleDeg = 180;
    EXPECT_EQ(sm::smoothMesh(*steep, d).singularNodes, 1u);
  }
}

TEST(MgaSmooth, BadInput) {
  const auto mp = toMesh(grid(5, 0.2, 1));
  const CMeshO& m = *mp;
  sm::Options o;
  o.population = 2;
  EXPECT_THROW(sm::smoothMesh(m, o), pectus::InputError);
  o = sm::Options();
  o.accuracy = 0;
  EXPECT_THROW(sm::smoothMesh(m, o), pectus::InputError);
  o = sm::Options();
  o.maxSweeps = 0;
  EXPECT_THROW(sm::smoothMesh(m, o), pectus::InputError);
  o = sm::Options();
  o.singularAngleDeg = 0;
  EXPECT_THROW(sm::smoothMesh(m, o), pectus::InputError);
  o.singularAngleDeg = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(sm::smoothMesh(m, o), pectus::InputError);
  o = sm::Options();
  o.method = sm::Method::ConjugateGradient;
  o.cgIterations = 0;
  EXPECT_THROW(sm::smoothMesh(m, o), pectus::InputError);
  o.cgIterations = 10;
  o.featureAngleDeg = -1;
  EXPECT_THROW(sm::smoothMesh(m, o), pectus::InputError);
  o = sm::Options();
  o.method = sm::Method::ConjugateGradient;
  o.tolerance = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(sm::smoothMesh(m, o), pectus::InputError);

  // no free node: a single triangle (all boundary)
  TriMesh one;
  one.V = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  one.F = {{0, 1, 2}};
  try {
    sm::smoothMesh(*toMesh(one), sm::Options());
    FAIL() << "no free node accepted";
  } catch (const pectus::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no free node"), std::string::npos) << e.what();
  }
  // every node fixed by the selection (both methods)
  std::vector<char> all(m.vert.size(), 1);
  EXPECT_THROW(sm::smoothMesh(m, sm::Options(), all), pectus::InputError);
  sm::Options cgo;
  cgo.method = sm::Method::ConjugateGradient;
  EXPECT_THROW(sm::smoothMesh(m, cgo, all), pectus::InputError);
  // non-manifold and NaN input with the gradient method
  TriMesh nan2 = grid(5, 0.2, 1);
  nan2.V[7].y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(sm::smoothMesh(*toMesh(nan2), cgo), pectus::InputError);

  // NaN coordinate
  TriMesh nan = grid(5, 0.2, 1);
  nan.V[12].x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(sm::smoothMesh(*toMesh(nan), sm::Options()), pectus::InputError);

  // non-manifold edge: three faces on one edge
  TriMesh nm = grid(5, 0.0, 1);
  nm.V.emplace_back(0.5, 0.5, 1);
  nm.F.push_back({0, 6, int(nm.V.size() - 1)});  // the interior diagonal 0-6
  EXPECT_THROW(sm::smoothMesh(*toMesh(nm), sm::Options()), pectus::InputError);
}

// three closed surfaces 10 mm apart: a move that pushes a node of the first through the second is undone,
// a move on the third, which crosses nothing, stays, and crossings among unmoved nodes are left alone
TEST(MgaSmooth, RestoreCrossingsPutsBackTheNodesOfCrossingFaces) {
  const std::vector<Vec3> tet{{0, 0, 0}, {4, 0, 0}, {0, 4, 0}, {0, 0, 4}};
  std::vector<Vec3> before;
  for (double x : {0.0, 10.0, 20.0})
    for (const Vec3& p : tet) before.push_back(p + Vec3(x, 0, 0));
  std::vector<std::vector<int>> faces;
  for (int o : {0, 4, 8})
    for (const auto& f : std::vector<std::vector<int>>{{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}})
      faces.push_back({f[0] + o, f[1] + o, f[2] + o});
  std::vector<Vec3> after = before;
  after[1] = Vec3(11, 0.5, 0.5);  // through the second tet's faces
  after[9] = Vec3(24.5, 0, 0);    // crosses nothing
  const std::vector<int> back = pectus::smooth::restoreCrossings(faces, before, after);
  EXPECT_EQ(back, std::vector<int>{1});
  EXPECT_EQ(after[1], before[1]);
  EXPECT_EQ(after[9], Vec3(24.5, 0, 0));

  // the input crossing itself (the second tet moved into the first), nothing moved: nothing to put back
  std::vector<Vec3> crossing = before;
  for (int i = 4; i < 8; ++i) crossing[std::size_t(i)] -= Vec3(9, 0, 0);
  std::vector<Vec3> same = crossing;
  EXPECT_TRUE(pectus::smooth::restoreCrossings(faces, crossing, same).empty());

  // a quad surface (a cube, quads split along v0-v2) with a corner pushed into the tet beside it
  std::vector<Vec3> cube{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  for (Vec3& p : cube) p = 3.0 * p + Vec3(-10, 0, 0);
  std::vector<Vec3> cb = cube;
  for (const Vec3& p : tet) cb.push_back(p);
  const std::vector<std::vector<int>> qf{{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7},
                                         {8, 10, 9}, {8, 9, 11}, {8, 11, 10}, {9, 10, 11}};
  std::vector<Vec3> ca = cb;
  ca[6] = Vec3(0.5, 0.5, 0.5);  // the cube's corner (1,1,1) into the tet
  EXPECT_EQ(pectus::smooth::restoreCrossings(qf, cb, ca), std::vector<int>{6});
  EXPECT_EQ(ca[6], cb[6]);
}
