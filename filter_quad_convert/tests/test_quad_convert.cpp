// Unit tests of the quad conversion core: matching optimality against brute force, conversion modes,
// all-quads output, structure operators, writer.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <sstream>

#include "pectus/quad/matching.h"
#include "pectus/errors.h"
#include "pectus/quad/poly_io.h"
#include "pectus/quad/poly_mesh.h"
#include "pectus/quad/quad_convert.h"
#include "pectus/quad/structure.h"

using namespace pectus;
using namespace pectus::quad;

namespace {

/// (n+1)^2 nodes on [0,n]^2, interior jittered by up to `jitter`, z = height(x, y); alternating diagonals
c1::TriMesh gridTri(int n, double jitter, unsigned seed, std::function<double(double, double)> height = {},
                    bool alternate = true) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(-jitter, jitter);
  c1::TriMesh t;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      double x = i, y = j;
      if (i > 0 && i < n && j > 0 && j < n) {
        x += U(rng);
        y += U(rng);
      }
      t.V.push_back({x, y, height ? height(x, y) : 0.0});
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      if (!alternate || (i + j) % 2 == 0) {
        t.F.push_back({a, b, c});
        t.F.push_back({a, c, d});
      } else {
        t.F.push_back({a, b, d});
        t.F.push_back({b, c, d});
      }
    }
  return t;
}

/// brute force: max cardinality, then max weight, over all matchings (small graphs)
std::pair<int, double> bruteForce(int n, const std::vector<WeightedEdge>& edges) {
  std::pair<int, double> best{0, 0.0};
  std::vector<char> used(n, 0);
  std::function<void(std::size_t, int, double)> rec = [&](std::size_t i, int k, double w) {
    if (k > best.first || (k == best.first && w > best.second + 1e-9)) best = {k, w};
    for (std::size_t j = i; j < edges.size(); ++j) {
      const auto& e = edges[j];
      if (used[e.a] || used[e.b]) continue;
      used[e.a] = used[e.b] = 1;
      rec(j + 1, k + 1, w + e.w);
      used[e.a] = used[e.b] = 0;
    }
  };
  rec(0, 0, 0.0);
  return best;
}

std::size_t valenceEnergy(const PolyMesh& m, int ideal) {
  std::vector<int> v;
  std::vector<char> b;
  valences(m, v, b);
  std::size_t e = 0;
  for (std::size_t i = 0; i < v.size(); ++i)
    if (!b[i] && v[i] > 0) e += std::size_t((v[i] - ideal) * (v[i] - ideal));
  return e;
}

PolyMesh asPoly(const c1::TriMesh& t) {
  PolyMesh p;
  p.V = t.V;
  for (const auto& f : t.F) {
    Poly q;
    q.nv = 3;
    q.v = {f[0], f[1], f[2], -1};
    p.F.push_back(q);
  }
  return p;
}

/// the unit square as two triangles sharing the diagonal 0-2: one quad
c1::TriMesh squarePair() {
  c1::TriMesh pair;
  pair.V = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  pair.F = {{0, 1, 2}, {0, 2, 3}};
  return pair;
}

const ConvertOptions kBothModes[] = {ConvertOptions{Pairing::Greedy, Leftovers::QuadDominant}, ConvertOptions{}};

}  // namespace

TEST(quad_matching, MaxCardinalityMaxWeightEqualsBruteForce) {
  std::mt19937 rng(11);
  int perfect = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const int n = 2 + int(rng() % 9);
    std::vector<WeightedEdge> edges;
    for (int a = 0; a < n; ++a)
      for (int b = a + 1; b < n; ++b)
        if (rng() % 100 < 40) edges.push_back({a, b, double(rng() % 1000) / 1000.0});
    const auto bf = bruteForce(n, edges);
    const auto mate = maxWeightMatching(n, edges, true);
    int pairs = 0;
    const double w = matchingWeight(mate, edges, &pairs);
    for (int i = 0; i < n; ++i)
      if (mate[i] >= 0) ASSERT_EQ(mate[mate[i]], i);
    ASSERT_EQ(pairs, bf.first) << "trial " << trial;
    ASSERT_NEAR(w, bf.second, 1e-5) << "trial " << trial;
    perfect += 2 * pairs == n;
  }
  EXPECT_GT(perfect, 20);  // the random graphs include perfect-matchable ones
}

TEST(quad_matching, GreedyIsNeverBetterAndCanBeWorse) {
  // path a-b-c-d: greedy takes the heavy middle edge (1 pair), the optimum takes both ends (2 pairs)
  std::vector<WeightedEdge> e{{0, 1, 0.6}, {1, 2, 0.9}, {2, 3, 0.6}};
  int pg = 0, po = 0;
  matchingWeight(greedyMatching(4, e), e, &pg);
  matchingWeight(maxWeightMatching(4, e, true), e, &po);
  EXPECT_EQ(pg, 1);
  EXPECT_EQ(po, 2);
  // without the cardinality priority the heavier single edge... 0.9 < 1.2: still both ends
  int pw = 0;
  EXPECT_NEAR(matchingWeight(maxWeightMatching(4, e, false), e, &pw), 1.2, 1e-9);
}

TEST(quad_convert, OptimalGivesAllQuadsOnAJitteredGrid) {
  const auto t = gridTri(10, 0.3, 5, [](double x, double y) { return 0.05 * x * x - 0.03 * y * y; });
  ConvertOptions o;
  o.pairing = Pairing::Optimal;
  o.leftovers = Leftovers::QuadDominant;
  const auto r = convertToQuads(t, o);
  EXPECT_EQ(r.leftoverTriangles, 0u);
  EXPECT_EQ(r.mesh.quads(), 100u);
  EXPECT_DOUBLE_EQ(r.stats.quadPercent, 100.0);
  EXPECT_EQ(r.stats.invalidQuads, 0u);
  EXPECT_GT(r.stats.beta.mean, 0.75);
  EXPECT_FALSE(r.subdivided);
  // greedy: never more total beta over a perfect matching than the optimum
  o.pairing = Pairing::Greedy;
  const auto g = convertToQuads(t, o);
  EXPECT_LE(g.totalBeta, r.totalBeta + 1e-9);
  EXPECT_LE(g.merged, r.merged);
  EXPECT_EQ(g.stats.invalidQuads, 0u);
}

TEST(quad_convert, AllQuadsSplitsLeftoversWithNodesOnTheSurface) {
  // odd triangle count: one triangle removed from a paraboloid grid, so no perfect matching exists
  const auto h = [](double x, double y) { return 0.04 * ((x - 4) * (x - 4) + (y - 4) * (y - 4)); };
  auto t = gridTri(8, 0.25, 3, h);
  t.F.erase(t.F.begin() + 40);
  ConvertOptions o;
  o.leftovers = Leftovers::QuadDominant;
  const auto qd = convertToQuads(t, o);
  EXPECT_GE(qd.leftoverTriangles, 1u);
  EXPECT_LT(qd.stats.quadPercent, 100.0);
  EXPECT_EQ(qd.stats.invalidQuads, 0u);

  o.leftovers = Leftovers::AllQuads;
  const auto r = convertToQuads(t, o);
  EXPECT_TRUE(r.subdivided);
  EXPECT_EQ(r.mesh.triangles(), 0u);
  EXPECT_DOUBLE_EQ(r.stats.quadPercent, 100.0);
  EXPECT_EQ(r.stats.invalidQuads, 0u);
  EXPECT_GT(r.stats.beta.min, 0.0);
  EXPECT_EQ(r.mesh.F.size(), 4 * qd.mesh.quads() + 3 * qd.mesh.triangles());
  // new nodes lie on the smooth surface (the C1 surface of a fine paraboloid mesh is close to it)
  double dev = 0;
  for (std::size_t i = t.V.size(); i < r.mesh.V.size(); ++i)
    dev = std::max(dev, std::abs(r.mesh.V[i].z() - h(r.mesh.V[i].x(), r.mesh.V[i].y())));
  EXPECT_LT(dev, 5e-3);
  EXPECT_GT(r.newNodes, 0u);
}

TEST(quad_convert, NeverMakesNonConvexQuads) {
  // a dart: the two triangles (0,1,2) and (0,2,3) make a non-convex quad 0-1-2-3
  c1::TriMesh t;
  t.V = {{0, 0, 0}, {2, -1, 0}, {0.5, 0, 0}, {2, 1, 0}};
  t.F = {{0, 1, 2}, {0, 2, 3}};
  EXPECT_TRUE(quadCandidates(t, {}).empty());
  EXPECT_THROW(convertToQuads(t, {}), InputError);
  // a convex pair is accepted
  t.V[2] = {3, 0, 0};
  ASSERT_EQ(quadCandidates(t, {}).size(), 1u);
  EXPECT_GT(quadCandidates(t, {})[0].beta, 0.3);
}

TEST(quad_convert, BadInput) {
  c1::TriMesh empty;
  EXPECT_THROW(convertToQuads(empty, {}), InputError);
  c1::TriMesh isolated;  // two triangles without a common edge
  isolated.V = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {5, 0, 0}, {6, 0, 0}, {5, 1, 0}};
  isolated.F = {{0, 1, 2}, {3, 4, 5}};
  try {
    convertToQuads(isolated, {});
    FAIL() << "no throw";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("isolated"), std::string::npos);
  }
  // a NaN vertex must not go through into the output, a bad index must not be read out of range
  const auto pair = squarePair();
  for (const ConvertOptions& o : kBothModes) {
    auto nan = pair;
    nan.V[3].y() = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(convertToQuads(nan, o), InputError);
    auto bad = pair;
    bad.F[1][2] = 4;
    EXPECT_THROW(convertToQuads(bad, o), InputError);
    bad.F[1][2] = -1;
    EXPECT_THROW(convertToQuads(bad, o), InputError);
    EXPECT_EQ(convertToQuads(pair, o).merged, 1u);
    // the input of tests/fuzz/corpus/quad/collapsed-leftover-triangle: a triangle with a vertex twice, which
    // must not go through as a leftover element with that vertex twice
    auto collapsed = pair;
    collapsed.V.push_back({0.5, -1, 0.3});
    collapsed.F.push_back({4, 4, 1});
    EXPECT_THROW(convertToQuads(collapsed, o), InputError);
  }
}

TEST(quad_convert, UnusedInfVertexIsRefused) {
  // the input of tests/fuzz/corpus/quad/unused-inf-vertex is a 3 x 4 torus whose vertex 4, welded into vertex
  // 10 so no triangle uses it, has z = Inf: the conversion copies every vertex into its output, so a NaN check
  // of only the vertices the triangles use would let the Inf through (MeshLab's layer check refuses it; a
  // direct caller would get it back). Here: a square pair with an unused vertex at Inf.
  auto t = squarePair();
  t.V.push_back({0.63, -0.0094, std::numeric_limits<double>::infinity()});
  for (const ConvertOptions& o : kBothModes) {
    try {
      const auto r = convertToQuads(t, o);
      FAIL() << "no throw; output vertex 4 = " << r.mesh.V[4].transpose();
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("vertex 4 has a NaN or infinite coordinate"), std::string::npos) << e.what();
    }
  }
  t.V[4].z() = 0.5;  // a finite unused vertex is kept as it is
  for (const ConvertOptions& o : kBothModes) {
    const auto r = convertToQuads(t, o);
    EXPECT_EQ(r.merged, 1u);
    ASSERT_EQ(r.mesh.V.size(), 5u);
    EXPECT_EQ(r.mesh.V[4], t.V[4]);
  }
}

TEST(quad_convert, DihedralLimitKeepsCreases) {
  c1::TriMesh t;  // two triangles folded by 90 degrees
  t.V = {{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, 0, -1}};
  t.F = {{0, 1, 2}, {1, 0, 3}};
  ConvertOptions o;
  o.maxDihedralDeg = 60;
  EXPECT_TRUE(quadCandidates(t, o).empty());
  o.maxDihedralDeg = 120;
  EXPECT_EQ(quadCandidates(t, o).size(), 1u);
}

TEST(quad_polymesh, CMeshRoundTripKeepsQuads) {
  const auto t = gridTri(4, 0.2, 1);
  const auto r = convertToQuads(t, {});
  CMeshO m;
  toCMesh(r.mesh, m);
  EXPECT_EQ(m.FN(), 32);
  int faux = 0;
  for (const auto& f : m.face)
    for (int k = 0; k < 3; ++k) faux += f.IsF(k);
  EXPECT_EQ(faux, 32);  // one faux edge per face
  const auto back = fromCMesh(m, true);
  ASSERT_EQ(back.F.size(), r.mesh.F.size());
  EXPECT_EQ(back.quads(), 16u);
  for (std::size_t i = 0; i < back.F.size(); ++i)
    EXPECT_NEAR(polyQuality(back, back.F[i]), polyQuality(r.mesh, r.mesh.F[i]), 1e-6);
}

TEST(quad_structure, TriangleOperatorsImproveValenceAndQuality) {
  // alternating diagonals: interior valences 4 and 8; edge swaps move them toward 6
  auto t = gridTri(8, 0.0, 1, {}, true);
  const auto pm = asPoly(t);
  StructureOptions o;
  o.eliminate = o.divide = false;
  const auto r = improveStructure(pm, nullptr, o);
  EXPECT_GT(r.swaps, 5u);
  EXPECT_LT(valenceEnergy(r.mesh, 6), valenceEnergy(pm, 6));
  EXPECT_GE(r.after.alpha.min, r.before.alpha.min - 1e-12);
  EXPECT_EQ(r.mesh.F.size(), pm.F.size());
}

TEST(quad_structure, TriangleNodeEliminationRemovesValence3Nodes) {
  auto t = gridTri(6, 0.1, 2, {}, false);
  // insert a node in the middle of 3 interior triangles: three valence-3 nodes
  for (int f : {20, 31, 44}) {
    const auto tri = t.F[f];
    const int v = int(t.V.size());
    t.V.push_back((t.V[tri[0]] + t.V[tri[1]] + t.V[tri[2]]) / 3.0);
    t.F[f] = {tri[0], tri[1], v};
    t.F.push_back({tri[1], tri[2], v});
    t.F.push_back({tri[2], tri[0], v});
  }
  const auto pm = asPoly(t);
  StructureOptions o;
  o.swap = o.divide = false;
  const auto r = improveStructure(pm, nullptr, o);
  EXPECT_EQ(r.eliminations, 3u);
  EXPECT_EQ(r.mesh.F.size(), pm.F.size() - 6);
  EXPECT_EQ(r.mesh.V.size(), pm.V.size() - 3);
  EXPECT_GT(r.after.alpha.min, r.before.alpha.min + 0.1);
  EXPECT_EQ(r.after.valence[3], 0u);
}

TEST(quad_structure, TriangleEdgeDividingSplitsLongEdges) {
  // a thin rhombus across a long edge: two obtuse triangles; dividing the long diagonal helps
  c1::TriMesh t;
  t.V = {{0, 0, 0}, {4, 0, 0}, {2, 0.6, 0}, {2, -0.6, 0}, {-1, 1, 0}, {5, 1, 0}, {5, -1, 0}, {-1, -1, 0}};
  t.F = {{0, 1, 2}, {1, 0, 3}, {0, 2, 4}, {2, 1, 5}, {1, 3, 6}, {3, 0, 7}};
  const auto pm = asPoly(t);
  StructureOptions o;
  o.swap = o.eliminate = false;
  o.longEdgeFactor = 1.2;
  const auto r = improveStructure(pm, nullptr, o);
  EXPECT_EQ(r.divisions, 1u);
  EXPECT_EQ(r.mesh.F.size(), pm.F.size() + 2);
  EXPECT_GT(r.after.alpha.min, r.before.alpha.min);
}

namespace {
PolyMesh quadGrid(int n) {
  PolyMesh q;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) q.V.push_back({double(i), double(j), 0.0});
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i;
      Poly p;
      p.nv = 4;
      p.v = {a, a + 1, a + n + 2, a + n + 1};
      q.F.push_back(p);
    }
  return q;
}
}  // namespace

TEST(quad_structure, QuadEdgeSwapRestoresTheGrid) {
  // the 2x1 block of quads (2,2),(3,2) split by its other diagonal: valences 5, 5, 3, 3 -> a swap gives 4s
  PolyMesh q = quadGrid(6);
  const int a = 2 * 7 + 2;
  q.V[a + 1].y() -= 0.2;
  q.V[a + 8].y() += 0.2;
  Poly p0, p1;
  p0.nv = p1.nv = 4;
  p0.v = {a, a + 1, a + 2, a + 9};
  p1.v = {a + 9, a + 8, a + 7, a};
  q.F[2 * 6 + 2] = p0;
  q.F[2 * 6 + 3] = p1;
  ASSERT_GT(polyStats(q).beta.min, 0.0);
  StructureOptions o;
  o.eliminate = o.divide = false;
  const auto r = improveStructure(q, nullptr, o);
  EXPECT_EQ(r.swaps, 1u);
  EXPECT_EQ(valenceEnergy(q, 4), 4u);
  EXPECT_EQ(valenceEnergy(r.mesh, 4), 0u);
  EXPECT_GT(r.after.beta.min, r.before.beta.min);
}

TEST(quad_structure, QuadOperators) {
  // quad grid; one quad split into three around a centre node (valence 3): node elimination undoes it
  PolyMesh q = quadGrid(6);
  // merge two quads (2,2),(3,2) into a hexagon split by a centre node into 3 quads
  const int a = 2 * 7 + 2;
  const int H[6] = {a, a + 1, a + 2, a + 9, a + 8, a + 7};  // hexagon around the 2x1 block
  q.V[a + 1].y() -= 0.3;  // make the hexagon strictly convex
  q.V[a + 8].y() += 0.3;
  const int c = int(q.V.size());
  q.V.push_back({3.0, 2.5, 0.0});
  std::vector<Poly> F;
  for (std::size_t f = 0; f < q.F.size(); ++f)
    if (f != 2 * 6 + 2 && f != 2 * 6 + 3) F.push_back(q.F[f]);
  for (int s = 0; s < 6; s += 2) {
    Poly p;
    p.nv = 4;
    p.v = {c, H[s], H[s + 1], H[(s + 2) % 6]};
    F.push_back(p);
  }
  q.F = F;
  ASSERT_GT(polyStats(q).beta.min, 0.0);
  StructureOptions o;
  o.swap = o.divide = false;
  const auto r = improveStructure(q, nullptr, o);
  EXPECT_EQ(r.eliminations, 1u);
  EXPECT_EQ(r.mesh.F.size(), 36u);
  EXPECT_EQ(r.after.valence[3], 0u);
  EXPECT_GT(r.after.beta.min, r.before.beta.min);
  EXPECT_EQ(r.after.invalidQuads, 0u);
}

TEST(quad_structure, BadInputIsRefused) {
  // the structure operators check their input: a NaN node must not go through into the output, a bad index
  // or a pentagon must not be read out of range
  StructureOptions o;
  PolyMesh nan = quadGrid(3), badIndex = quadGrid(3), repeated = quadGrid(3), pentagon = quadGrid(3);
  nan.V[5].x() = std::numeric_limits<double>::quiet_NaN();  // an interior node
  badIndex.F[4].v[2] = int(badIndex.V.size());
  repeated.F[4].v[2] = repeated.F[4].v[0];
  pentagon.F[4].nv = 5;
  for (const PolyMesh* q : {&nan, &badIndex, &repeated, &pentagon}) EXPECT_THROW(improveStructure(*q, nullptr, o), InputError);
  EXPECT_EQ(improveStructure(quadGrid(3), nullptr, o).mesh.F.size(), 9u);
}

TEST(quad_structure, QuadEdgeSwapTowardValence4) {
  // a converted jittered mesh: swaps lower the valence energy and never the worst beta
  const auto t = gridTri(12, 0.35, 9);
  ConvertOptions co;
  co.pairing = Pairing::Greedy;
  co.leftovers = Leftovers::QuadDominant;
  co.minQuality = 0.0;
  auto conv = convertToQuads(t, co);
  StructureOptions o;
  const auto r = improveStructure(conv.mesh, nullptr, o);
  EXPECT_EQ(r.after.invalidQuads, 0u);
  EXPECT_GE(r.after.beta.min, r.before.beta.min - 1e-12);
  EXPECT_LE(valenceEnergy(r.mesh, 4), valenceEnergy(conv.mesh, 4));
  EXPECT_GT(r.swaps + r.eliminations + r.divisions, 0u);
  EXPECT_GT(r.after.beta.mean, r.before.beta.mean);
  std::printf("quad structure: swaps %zu eliminations %zu divisions %zu; energy %zu -> %zu; beta min %.3f -> %.3f mean %.3f -> %.3f\n",
              r.swaps, r.eliminations, r.divisions, valenceEnergy(conv.mesh, 4), valenceEnergy(r.mesh, 4),
              r.before.beta.min, r.after.beta.min, r.before.beta.mean, r.after.beta.mean);
}

TEST(quad_writer, OffObjVtk) {
  const auto t = gridTri(3, 0.0, 1);
  const auto r = convertToQuads(t, {});
  const std::string dir = ::testing::TempDir();
  writePolyMesh(dir + "q.off", r.mesh, PolyFormat::OFF);
  std::ifstream in(dir + "q.off");
  std::string magic;
  std::size_t nv, nf, ne;
  in >> magic >> nv >> nf >> ne;
  EXPECT_EQ(magic, "OFF");
  EXPECT_EQ(nv, 16u);
  EXPECT_EQ(nf, 9u);
  double x;
  for (std::size_t i = 0; i < 3 * nv; ++i) in >> x;
  int k, quads = 0;
  for (std::size_t i = 0; i < nf; ++i) {
    in >> k;
    quads += k == 4;
    for (int j = 0; j < k; ++j) in >> x;
  }
  EXPECT_EQ(quads, 9);
  writePolyMesh(dir + "q.obj", r.mesh, PolyFormat::OBJ);
  std::ifstream obj(dir + "q.obj");
  std::string line;
  int fl = 0;
  while (std::getline(obj, line))
    if (line.rfind("f ", 0) == 0) {
      std::istringstream s(line.substr(2));
      int a, cnt = 0;
      while (s >> a) ++cnt;
      fl += cnt == 4;
    }
  EXPECT_EQ(fl, 9);
  writePolyMesh(dir + "q.vtk", r.mesh, PolyFormat::VTK);
  std::ifstream vtk(dir + "q.vtk");
  std::stringstream all;
  all << vtk.rdbuf();
  EXPECT_NE(all.str().find("POLYGONS 9 45"), std::string::npos);
  EXPECT_THROW(writePolyMesh("/nonexistent-dir/q.obj", r.mesh, PolyFormat::OBJ), InputError);
}

TEST(quad_polymesh, FauxDiagonalsNeverCollide) {
  // two quads around a node b of valence 2 whose stored diagonals are the same edge p-q
  PolyMesh m;
  m.V = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 2, 0}, {-1, -1, 0}};  // b p q c d
  Poly q1, q2;
  q1.nv = q2.nv = 4;
  q1.v = {1, 3, 2, 0};  // p c q b: diagonal p-q
  q2.v = {2, 4, 1, 0};  // q d p b: diagonal q-p
  m.F = {q1, q2};
  CMeshO cm;
  toCMesh(m, cm);
  PolyMesh back;
  ASSERT_NO_THROW(back = fromCMesh(cm, true));
  EXPECT_EQ(back.quads(), 2u);
}

TEST(quad_convert, AllQuadsSplitNeverInvalidOnACurvedClosedSurface) {
  // a coarse, jittered UV sphere with one triangle removed: strongly curved, an odd count; the split must still give only valid quads
  c1::TriMesh t;
  const int nu = 10, nvv = 7;
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> U(-0.15, 0.15);
  t.V.push_back({0, 0, 1});
  for (int j = 1; j < nvv; ++j)
    for (int i = 0; i < nu; ++i) {
      const double th = M_PI * (j + U(rng)) / nvv, ph = 2 * M_PI * (i + U(rng)) / nu;
      t.V.push_back({std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)});
    }
  t.V.push_back({0, 0, -1});
  const int S = int(t.V.size()) - 1;
  const auto id = [&](int j, int i) { return 1 + (j - 1) * nu + (i % nu); };
  for (int i = 0; i < nu; ++i) t.F.push_back({0, id(1, i), id(1, i + 1)});
  for (int j = 1; j < nvv - 1; ++j)
    for (int i = 0; i < nu; ++i) {
      t.F.push_back({id(j, i), id(j + 1, i), id(j + 1, i + 1)});
      t.F.push_back({id(j, i), id(j + 1, i + 1), id(j, i + 1)});
    }
  for (int i = 0; i < nu; ++i) t.F.push_back({S, id(nvv - 1, i + 1), id(nvv - 1, i)});
  t.F.erase(t.F.begin() + 7);  // odd count: no perfect matching
  ConvertOptions o;
  const auto r = convertToQuads(t, o);
  EXPECT_TRUE(r.subdivided);
  EXPECT_DOUBLE_EQ(r.stats.quadPercent, 100.0);
  EXPECT_EQ(r.stats.invalidQuads, 0u);
  CMeshO cm;
  toCMesh(r.mesh, cm);
  EXPECT_EQ(fromCMesh(cm, true).quads(), r.mesh.quads());
}
