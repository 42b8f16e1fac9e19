// Faux-edge quads, element quality and mesh checks on small CMeshO meshes built in code.
#include <gtest/gtest.h>

#include <vcg/complex/complex.h>

#include <cmath>
#include <set>

#include "pectus/element_quality.h"
#include "pectus/errors.h"
#include "pectus/folds.h"
#include "pectus/mesh_checks.h"

namespace {

// n x n grid of unit squares in the plane z=0, each split along its diagonal; faux diagonal if quads
void grid(CMeshO& m, int n, bool quads, double h = 1.0) {
  auto vi = vcg::tri::Allocator<CMeshO>::AddVertices(m, (n + 1) * (n + 1));
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.vert[j * (n + 1) + i].P() = Point3m(Scalarm(i * h), Scalarm(j * h), 0);
  (void)vi;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      auto f = vcg::tri::Allocator<CMeshO>::AddFaces(m, 2);
      f->V(0) = &m.vert[a]; f->V(1) = &m.vert[b]; f->V(2) = &m.vert[c];
      if (quads) f->SetF(2);  // edge c-a
      ++f;
      f->V(0) = &m.vert[a]; f->V(1) = &m.vert[c]; f->V(2) = &m.vert[d];
      if (quads) f->SetF(0);  // edge a-c
    }
}

}  // namespace

TEST(Elements, TrianglesOnePerFace) {
  CMeshO m;
  grid(m, 3, false);
  auto em = pectus::buildElements(m, pectus::ElementKind::Triangles);
  EXPECT_EQ(em.elements.size(), 18u);
  EXPECT_EQ(em.quads(), 0u);
  EXPECT_FALSE(pectus::hasFauxEdges(m));
}

TEST(Elements, FauxPairsBecomeQuadsInBoundaryOrder) {
  CMeshO m;
  grid(m, 3, true);
  ASSERT_TRUE(pectus::hasFauxEdges(m));
  auto em = pectus::buildElements(m, pectus::ElementKind::Quads);
  ASSERT_EQ(em.elements.size(), 9u);
  EXPECT_EQ(em.quads(), 9u);
  // first square: a=0, b=1, c=5, d=4 -> boundary must visit all four corners in a cycle
  const auto& e = em.elements[0];
  std::set<int> vs(e.v.begin(), e.v.end());
  EXPECT_EQ(vs, (std::set<int>{0, 1, 4, 5}));
  for (int k = 0; k < 4; ++k) {  // consecutive corners are grid neighbours (not the diagonal 0-5 or 1-4)
    EXPECT_FALSE((e.v[k] == 0 && e.v[(k + 1) % 4] == 5) || (e.v[k] == 5 && e.v[(k + 1) % 4] == 0));
    EXPECT_FALSE((e.v[k] == 1 && e.v[(k + 1) % 4] == 4) || (e.v[k] == 4 && e.v[(k + 1) % 4] == 1));
  }
}

TEST(ElementQuality, UnitGridQuadsAreOneAndTrianglesAreRightIsosceles) {
  CMeshO mq;
  grid(mq, 4, true);
  auto q = pectus::computeElementQuality(mq, pectus::ElementKind::Quads);
  EXPECT_NEAR(q.stats.min, 1.0, 1e-6);
  EXPECT_NEAR(q.stats.max, 1.0, 1e-6);
  EXPECT_EQ(q.stats.histogram[9], 16u);
  for (double v : q.perFace) EXPECT_NEAR(v, 1.0, 1e-6);

  CMeshO mt;
  grid(mt, 4, false);
  auto t = pectus::computeElementQuality(mt, pectus::ElementKind::Triangles);
  EXPECT_EQ(t.perElement.size(), 32u);
  EXPECT_NEAR(t.stats.mean, std::sqrt(3.0) / 2, 1e-6);
  EXPECT_EQ(t.stats.histogram[8], 32u);
}

TEST(ElementQuality, MovedVertexLowersQuality) {
  CMeshO m;
  grid(m, 2, true);
  m.vert[4].P() = Point3m(0.2f, 0.2f, 0);  // centre vertex pushed toward a corner
  auto q = pectus::computeElementQuality(m, pectus::ElementKind::Quads);
  EXPECT_LT(q.stats.min, 0.6);
  EXPECT_NEAR(q.stats.max, q.perElement[3], 1e-12);  // the far quad grows; stays valid
}

TEST(Elements, BrokenFauxEdgesAreRejected) {
  CMeshO m;
  grid(m, 1, true);
  m.face[1].ClearF(0);  // only one side of the pair is faux
  EXPECT_THROW(pectus::buildElements(m, pectus::ElementKind::Quads), pectus::InputError);
  CMeshO b;
  grid(b, 1, false);
  b.face[0].SetF(0);  // a faux boundary edge
  EXPECT_THROW(pectus::buildElements(b, pectus::ElementKind::Quads), pectus::InputError);
}

TEST(MeshChecks, DetectsBadInput) {
  CMeshO empty;
  EXPECT_THROW(pectus::requireMesh(empty, {}, "x"), pectus::InputError);

  CMeshO pts;
  vcg::tri::Allocator<CMeshO>::AddVertices(pts, 3);
  EXPECT_THROW(pectus::requireMesh(pts, {}, "x"), pectus::InputError);

  CMeshO g;
  grid(g, 2, false);
  auto r = pectus::inspectMesh(g);
  EXPECT_EQ(r.faces, 8u);
  EXPECT_EQ(r.boundaryEdges, 8u);
  EXPECT_EQ(r.nonManifoldEdges, 0u);
  EXPECT_EQ(r.nonManifoldVertices, 0u);
  pectus::MeshRequirements closed;
  closed.closed = true;
  EXPECT_THROW(pectus::requireMesh(g, closed, "x"), pectus::InputError);

  // a third face on the interior diagonal 0-4 makes it non-manifold
  auto f = vcg::tri::Allocator<CMeshO>::AddFaces(g, 1);
  auto v = vcg::tri::Allocator<CMeshO>::AddVertices(g, 1);
  v->P() = Point3m(0.5f, 0, 1);
  f->V(0) = &g.vert[0]; f->V(1) = &g.vert[4]; f->V(2) = &*v;
  r = pectus::inspectMesh(g);
  EXPECT_EQ(r.nonManifoldEdges, 1u);
  pectus::MeshRequirements man;
  man.edgeManifold = true;
  EXPECT_THROW(pectus::requireMesh(g, man, "x"), pectus::InputError);

  CMeshO nanm;
  grid(nanm, 1, false);
  nanm.vert[0].P()[0] = std::nanf("");
  EXPECT_THROW(pectus::requireMesh(nanm, {}, "x"), pectus::InputError);

  // a face repeated (vertices in another order): reported as a duplicate, before the non-manifold edges
  CMeshO dup;
  grid(dup, 2, false);
  auto d = vcg::tri::Allocator<CMeshO>::AddFaces(dup, 1);
  d->V(0) = dup.face[3].V(1); d->V(1) = dup.face[3].V(2); d->V(2) = dup.face[3].V(0);
  r = pectus::inspectMesh(dup);
  EXPECT_EQ(r.duplicateFaces, 1u);
  try {
    pectus::requireMesh(dup, man, "x");
    ADD_FAILURE() << "no error";
  } catch (const pectus::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("1 duplicate faces"), std::string::npos) << e.what();
  }
}

TEST(Folds, AnElementFacingAgainstItsEdgeNeighboursIsAFold) {
  // a 4 x 4 grid of triangles in z = 0: no fold; one interior node pushed past a neighbour flips the
  // triangles on that side, each facing against its neighbours; quads: the normal of the diagonals
  const int n = 4;
  std::vector<pectus::Vec3> X;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) X.emplace_back(i, j, 0);
  std::vector<pectus::Element> tris, quads;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      pectus::Element t1, t2, q;
      t1.v = {a, b, c, -1};
      t2.v = {a, c, d, -1};
      q.nv = 4;
      q.v = {a, b, c, d};
      tris.push_back(t1);
      tris.push_back(t2);
      quads.push_back(q);
    }
  const pectus::Folds ft(tris, X.size()), fq(quads, X.size());
  EXPECT_EQ(ft.count(X), 0u);
  EXPECT_EQ(fq.count(X), 0u);
  const int v = 2 * (n + 1) + 2;  // the centre node (2, 2)
  std::vector<int> readers;
  ft.readers(v, readers);
  EXPECT_EQ(readers.size(), 6u + 6u);  // its 6 triangles and the 6 across their outer edges
  std::vector<pectus::Vec3> Y = X;
  Y[std::size_t(v)] = pectus::Vec3(3.6, 2, 0);  // past its neighbour (3, 2)
  const std::vector<char> f = ft.all(Y);
  std::size_t folded = 0;
  for (std::size_t e = 0; e < f.size(); ++e)
    if (f[e]) {
      ++folded;
      const pectus::Element& el = tris[e];
      EXPECT_TRUE(el.v[0] == v || el.v[1] == v || el.v[2] == v) << "a fold away from the moved node";
      EXPECT_LT(pectus::elementNormal(el, Y).z(), 0);
    }
  EXPECT_GE(folded, 2u);
  Y[std::size_t(v)] = pectus::Vec3(4.5, 2, 0);  // a quad's diagonals cross over further out
  EXPECT_GE(fq.count(Y), 2u);
  // lifted out of the plane by a little: tilted, not folded
  Y = X;
  Y[std::size_t(v)].z() = 0.3;
  EXPECT_EQ(ft.count(Y), 0u);
}
