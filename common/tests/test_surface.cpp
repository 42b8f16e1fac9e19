// The cores' surface type: its topology (edges, boundary, manifold, components) and the one conversion
// from and to CMeshO with its index maps.
#include <gtest/gtest.h>

#include <vcg/complex/complex.h>

#include <cmath>
#include <limits>

#include "pectus/self_intersections.h"
#include "pectus/surface.h"
#include "pectus/surface_cmesh.h"

namespace {
using pectus::Surface;
using pectus::Topology;
using V3 = Eigen::Vector3d;

Surface tetrahedron(const V3& o = V3::Zero()) {
  Surface s;
  s.V = {o, o + V3(1, 0, 0), o + V3(0, 1, 0), o + V3(0, 0, 1)};
  s.F = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  return s;
}

Surface twoTetrahedra() {
  Surface a = tetrahedron(), b = tetrahedron(V3(5, 0, 0));
  for (auto& p : b.V) a.V.push_back(p);
  for (auto f : b.F) a.F.push_back({f[0] + 4, f[1] + 4, f[2] + 4});
  return a;
}
}  // namespace

TEST(Topology, ClosedTetrahedron) {
  const Surface s = tetrahedron();
  const Topology t(s);
  EXPECT_EQ(t.badFace, -1);
  ASSERT_EQ(t.edges.size(), 6u);
  for (const auto& e : t.edges) {
    EXPECT_LT(e.a, e.b);
    EXPECT_EQ(e.faces, 2);
    EXPECT_GE(e.f1, 0);
  }
  EXPECT_EQ(t.boundaryEdges(), 0u);
  EXPECT_EQ(t.nonManifoldEdges(), 0u);
  EXPECT_TRUE(t.closedManifold());
  for (int v = 0; v < 4; ++v) {
    EXPECT_EQ(t.vfStart[std::size_t(v) + 1] - t.vfStart[std::size_t(v)], 3) << v;
    EXPECT_FALSE(t.boundary[std::size_t(v)]);
    EXPECT_FALSE(t.nonManifoldVertex[std::size_t(v)]);
  }
  // local edge l of face f is opposite its local vertex l
  for (int f = 0; f < 4; ++f)
    for (int l = 0; l < 3; ++l) {
      const auto& e = t.edges[std::size_t(t.faceEdge[std::size_t(f)][std::size_t(l)])];
      const int a = s.F[std::size_t(f)][std::size_t((l + 1) % 3)], b = s.F[std::size_t(f)][std::size_t((l + 2) % 3)];
      EXPECT_EQ(std::min(a, b), e.a);
      EXPECT_EQ(std::max(a, b), e.b);
    }
}

TEST(Topology, OpenSurfaceHasBoundary) {
  Surface s = tetrahedron();
  s.F.pop_back();
  const Topology t(s);
  EXPECT_EQ(t.boundaryEdges(), 3u);
  EXPECT_FALSE(t.closedManifold());
  int onBoundary = 0;
  for (char b : t.boundary) onBoundary += b;
  EXPECT_EQ(onBoundary, 3);
  for (char n : t.nonManifoldVertex) EXPECT_FALSE(n);
}

TEST(Topology, IndexOutOfRangeStopsTheBuild) {
  Surface s = tetrahedron();
  s.F[2][1] = 7;
  const Topology t(s);
  EXPECT_EQ(t.badFace, 2);
  EXPECT_EQ(t.badIndex, 7);
  EXPECT_TRUE(t.edges.empty());
  EXPECT_FALSE(t.closedManifold());
}

TEST(Topology, NonManifoldEdgeAndVertex) {
  Surface fin = tetrahedron();
  fin.V.push_back(V3(1, 1, -1));
  fin.F.push_back({0, 1, 4});  // a third face on edge (0, 1)
  const Topology t(fin);
  EXPECT_EQ(t.nonManifoldEdges(), 1u);
  for (int e = 0; e < int(t.edges.size()); ++e)
    if (t.edges[std::size_t(e)].faces == 3) {
      EXPECT_EQ(t.edges[std::size_t(e)].a, 0);
      EXPECT_EQ(t.edges[std::size_t(e)].b, 1);
      EXPECT_EQ(t.edgeFacesEnd(e) - t.edgeFacesBegin(e), 3);
    }
  EXPECT_FALSE(t.closedManifold());

  Surface bowtie;  // two triangles sharing only vertex 0
  bowtie.V = {V3(0, 0, 0), V3(1, 0, 0), V3(1, 1, 0), V3(-1, 0, 0), V3(-1, -1, 0)};
  bowtie.F = {{0, 1, 2}, {0, 3, 4}};
  const Topology b(bowtie);
  EXPECT_TRUE(b.nonManifoldVertex[0]);
  for (int v = 1; v < 5; ++v) EXPECT_FALSE(b.nonManifoldVertex[std::size_t(v)]) << v;
}

TEST(Topology, FansOfAClosedSurface) {
  const Topology t(twoTetrahedra());
  for (int v = 0; v < 8; ++v) EXPECT_EQ(t.fans[std::size_t(v)], 1) << v;
  Surface s = twoTetrahedra();
  s.V.push_back(V3(9, 9, 9));  // a vertex no face uses
  EXPECT_EQ(Topology(s).fans[8], 0);
}

TEST(Topology, FansOfABowTie) {
  // two tetrahedra glued at one vertex: every edge in two faces, vertex 0 in two closed fans. The count
  // test (nonManifoldVertex) cannot see it: the star has as many edges as faces.
  Surface s = twoTetrahedra();
  for (auto& f : s.F)
    for (int& v : f)
      if (v == 4) v = 0;
  s.V[4] = V3(9, 9, 9);  // now unused
  const Topology t(s);
  EXPECT_EQ(t.nonManifoldEdges(), 0u);
  EXPECT_EQ(t.boundaryEdges(), 0u);
  EXPECT_EQ(t.fans[0], 2);
  EXPECT_EQ(t.fans[4], 0);
  for (int v : {1, 2, 3, 5, 6, 7}) EXPECT_EQ(t.fans[std::size_t(v)], 1) << v;
  EXPECT_FALSE(t.nonManifoldVertex[0]);

  Surface open;  // two triangles sharing only vertex 0: two open fans, both tests see it
  open.V = {V3(0, 0, 0), V3(1, 0, 0), V3(1, 1, 0), V3(-1, 0, 0), V3(-1, -1, 0)};
  open.F = {{0, 1, 2}, {0, 3, 4}};
  const Topology b(open);
  EXPECT_EQ(b.fans[0], 2);
  EXPECT_TRUE(b.nonManifoldVertex[0]);
}

TEST(Topology, CollapsedEdgesOfDegenerateFaces) {
  Surface s = tetrahedron();
  s.F.push_back({0, 0, 1});  // one collapsed edge at 0
  s.F.push_back({2, 2, 2});  // three at 2
  const Topology t(s);
  EXPECT_EQ(t.collapsedEdges, (std::vector<int>{1, 0, 3, 0}));
  EXPECT_EQ(t.nonManifoldEdges(), 1u);  // (0, 1): two tetrahedron faces and (0, 0, 1) twice
  const Topology::EdgeUse u = t.edgeUse();
  EXPECT_EQ(u.once, 1u);           // the "(0, 0)" key
  EXPECT_EQ(u.moreThanTwice, 2u);  // (0, 1) and the "(2, 2)" key
  EXPECT_EQ(t.fans[2], 2);         // the tetrahedron's fan and the face (2, 2, 2)
}

TEST(Topology, ComponentsInFaceOrder) {
  Surface s = twoTetrahedra();
  std::swap(s.F[0], s.F[4]);  // the second piece's face comes first
  std::vector<int> comp;
  EXPECT_EQ(Topology(s).components(comp), 2);
  ASSERT_EQ(comp.size(), 8u);
  EXPECT_EQ(comp[0], 0);
  EXPECT_EQ(comp[1], 1);
  EXPECT_EQ(comp[4], 1);
  EXPECT_EQ(comp[7], 0);
}

TEST(SurfaceOf, IndexMapsAndVertexChoices) {
  pectus::OwnedMesh m;
  pectus::toMesh(twoTetrahedra(), m);
  ASSERT_EQ(m.vn, 8);
  ASSERT_EQ(m.fn, 8);
  // delete the first piece's faces and its vertex 1; make vertex 6 non-finite
  for (int f = 0; f < 4; ++f) vcg::tri::Allocator<CMeshO>::DeleteFace(m, m.face[std::size_t(f)]);
  vcg::tri::Allocator<CMeshO>::DeleteVertex(m, m.vert[1]);
  m.vert[6].P()[0] = std::numeric_limits<Scalarm>::quiet_NaN();

  std::vector<int> vOf, fOf;
  const Surface live = pectus::surfaceOf(m, {}, &vOf, &fOf);
  EXPECT_EQ(live.V.size(), 7u);
  EXPECT_EQ(vOf, (std::vector<int>{0, 2, 3, 4, 5, 6, 7}));
  EXPECT_EQ(fOf, (std::vector<int>{4, 5, 6, 7}));
  EXPECT_EQ(live.F[0], (std::array<int, 3>{3, 5, 4}));  // m.vert 4, 6, 5

  pectus::SurfaceOf all;
  all.vertices = pectus::SurfaceOf::Vertices::All;
  const Surface a = pectus::surfaceOf(m, all);
  EXPECT_EQ(a.V.size(), 8u);
  EXPECT_EQ(a.F[0], (std::array<int, 3>{4, 6, 5}));

  pectus::SurfaceOf used;
  used.vertices = pectus::SurfaceOf::Vertices::UsedByFaces;
  used.skipNonFiniteFaces = true;  // three of the four faces touch vertex 6
  const Surface u = pectus::surfaceOf(m, used, &vOf, &fOf);
  ASSERT_EQ(u.F.size(), 1u);
  EXPECT_EQ(fOf, (std::vector<int>{5}));
  EXPECT_EQ(vOf, (std::vector<int>{4, 5, 7}));  // the order face 5 = (4, 5, 7) uses them
  EXPECT_EQ(u.F[0], (std::array<int, 3>{0, 1, 2}));

  pectus::SurfaceOf some;
  some.keepFace = [](std::size_t f) { return f != 6; };
  EXPECT_EQ(pectus::surfaceOf(m, some).F.size(), 3u);
}

TEST(SurfaceOf, RoundTripThroughCMeshO) {
  const Surface s = tetrahedron(V3(1.5, -2, 3));
  pectus::OwnedMesh m;
  const std::vector<V3> normals(4, V3(0, 0, 1));
  pectus::toMesh(s, m, &normals);
  EXPECT_EQ(m.vert[2].N()[2], Scalarm(1));
  const Surface back = pectus::surfaceOf(m);
  EXPECT_EQ(back.F, s.F);
  for (std::size_t i = 0; i < s.V.size(); ++i) EXPECT_LT((back.V[i] - s.V[i]).norm(), 1e-6);
}

TEST(SurfaceOf, SelfIntersectingFacesOfACMeshO) {
  pectus::OwnedMesh m;
  pectus::toMesh(twoTetrahedra(), m);
  EXPECT_TRUE(pectus::selfIntersectingFaces(m).empty());
  Surface crossing = twoTetrahedra();
  for (std::size_t i = 4; i < 8; ++i) crossing.V[i] -= V3(4.8, -0.1, -0.1);  // the second pierces the first
  pectus::OwnedMesh c;
  pectus::toMesh(crossing, c);
  EXPECT_FALSE(pectus::selfIntersectingFaces(c).empty());
}

// the reusable check gives the one-shot check's pairs at every position of the points: two separate
// tetrahedra apart and then one piercing the other; and two touching at a corner, where the orientation
// splits the vertex (the copies meet at a point they do not share, which counts as a crossing)
TEST(SelfIntersections, OneMeshAtSeveralPositions) {
  auto same = [](const std::vector<pectus::FacePair>& x, const std::vector<pectus::FacePair>& y) {
    if (x.size() != y.size()) return false;
    for (std::size_t i = 0; i < x.size(); ++i)
      if (x[i].a != y[i].a || x[i].b != y[i].b) return false;
    return true;
  };
  Surface apart = twoTetrahedra();
  pectus::SelfIntersections separate(apart.V.size(), apart.F);
  EXPECT_TRUE(separate(apart.V).empty());
  Surface through = apart;
  for (std::size_t i = 4; i < 8; ++i) through.V[i] -= V3(4.8, -0.1, -0.1);  // the second pierces the first
  EXPECT_FALSE(separate(through.V).empty());
  EXPECT_TRUE(same(separate(through.V), pectus::selfIntersections(through.V, through.F)));
  EXPECT_TRUE(separate(apart.V).empty());

  Surface pinched = twoTetrahedra();
  for (auto& f : pinched.F)
    for (int& v : f)
      if (v == 4) v = 1;  // the second tetrahedron's corner (5, 0, 0) becomes the first's (1, 0, 0)
  pinched.V[4] = V3(-7, -7, -7);  // no face uses it any more
  for (std::size_t i = 5; i < 8; ++i) pinched.V[i] -= V3(4, 0, 0);
  pectus::SelfIntersections touching(pinched.V.size(), pinched.F);
  EXPECT_FALSE(touching(pinched.V).empty());
  Surface lifted = pinched;
  for (std::size_t i = 5; i < 8; ++i) lifted.V[i] += V3(0, 0.5, 0.5);
  for (const Surface* p : {&pinched, &lifted})
    EXPECT_TRUE(same(touching(p->V), pectus::selfIntersections(p->V, p->F)));
}

// a face turned against its neighbours (the mesh is then built through the soup's orientation) gives the
// same pairs as the consistently oriented surface (built face by face as given)
TEST(SelfIntersections, FaceTurnedOverGivesTheSamePairs) {
  Surface through = twoTetrahedra();
  for (std::size_t i = 4; i < 8; ++i) through.V[i] -= V3(4.8, -0.1, -0.1);  // the second pierces the first
  Surface turned = through;
  std::swap(turned.F[0][1], turned.F[0][2]);
  std::swap(turned.F[5][1], turned.F[5][2]);
  const auto oriented = pectus::selfIntersections(through.V, through.F);
  const auto mended = pectus::selfIntersections(turned.V, turned.F);
  ASSERT_FALSE(oriented.empty());
  ASSERT_EQ(oriented.size(), mended.size());
  for (std::size_t i = 0; i < oriented.size(); ++i) {
    EXPECT_EQ(oriented[i].a, mended[i].a);
    EXPECT_EQ(oriented[i].b, mended[i].b);
  }
}

// a whole check of a large mesh runs in two halves side by side: it gives the pairs that one check of all
// faces gives (involving every face), on both sides of the line where the halves meet and across it. The
// grid is longer along x, so it is split near x = 40; a node moved past its neighbours makes its faces
// overlap theirs.
TEST(SelfIntersections, LargeMeshInTwoHalvesGivesThePairsOfOneCheck) {
  const int nx = 80, ny = 40;  // 6400 triangles
  Surface grid;
  auto id = [&](int i, int j) { return j * (nx + 1) + i; };
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) grid.V.push_back(V3(i, j, 0));
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      grid.F.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      grid.F.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  pectus::SelfIntersections check(grid.V.size(), grid.F);
  EXPECT_TRUE(check(grid.V).empty());
  for (int i : {5, 39, 40, 75}) grid.V[std::size_t(id(i, 20))] += V3(2.5, 0.5, 0);
  const auto halves = check(grid.V);
  std::vector<int> every(grid.F.size());
  for (std::size_t t = 0; t < every.size(); ++t) every[t] = int(t);
  const auto one = check.involving(every, grid.V);
  ASSERT_FALSE(halves.empty());
  ASSERT_EQ(halves.size(), one.size());
  for (std::size_t i = 0; i < one.size(); ++i) EXPECT_TRUE(halves[i].a == one[i].a && halves[i].b == one[i].b) << i;
  int near[4] = {0, 0, 0, 0};  // pairs with a face at x < 20, 20..40, 40..60, > 60
  for (const auto& p : halves) ++near[std::min(3, int(grid.V[std::size_t(grid.F[std::size_t(p.a)][0])].x()) / 20)];
  for (int q = 0; q < 4; ++q) EXPECT_GT(near[q], 0) << q;
}

// the local check gives exactly the whole check's pairs that have one of the given faces in them: the second
// tetrahedron pierces the first, and each single face and the set of all faces are asked for in turn; a
// degenerate face asked for is reported with itself
TEST(SelfIntersections, InvolvingGivesTheWholeChecksPairsOfTheGivenFaces) {
  Surface through = twoTetrahedra();
  for (std::size_t i = 4; i < 8; ++i) through.V[i] -= V3(4.8, -0.1, -0.1);
  pectus::SelfIntersections check(through.V.size(), through.F);
  const auto all = check(through.V);
  ASSERT_FALSE(all.empty());
  std::size_t seen = 0;
  for (int t = 0; t < int(through.F.size()); ++t) {
    const auto mine = check.involving({t}, through.V);
    std::size_t expected = 0;
    for (const auto& p : all) expected += p.a == t || p.b == t;
    EXPECT_EQ(mine.size(), expected) << t;
    for (const auto& p : mine) EXPECT_TRUE(p.a == t || p.b == t) << t;
    seen += mine.size();
  }
  EXPECT_GE(seen, all.size());
  std::vector<int> every(through.F.size());
  for (std::size_t t = 0; t < every.size(); ++t) every[t] = int(t);
  const auto whole = check.involving(every, through.V);
  ASSERT_EQ(whole.size(), all.size());
  for (std::size_t i = 0; i < all.size(); ++i) EXPECT_TRUE(whole[i].a == all[i].a && whole[i].b == all[i].b);
  Surface apart = twoTetrahedra();
  EXPECT_TRUE(check.involving(every, apart.V).empty());  // the same check at other positions

  Surface collapsed = twoTetrahedra();
  collapsed.F[2] = {collapsed.F[2][0], collapsed.F[2][0], collapsed.F[2][1]};
  pectus::SelfIntersections withDegenerate(collapsed.V.size(), collapsed.F);
  const auto d = withDegenerate.involving({2}, collapsed.V);
  ASSERT_FALSE(d.empty());
  EXPECT_TRUE(d[0].a == 2 && d[0].b == 2);
}
