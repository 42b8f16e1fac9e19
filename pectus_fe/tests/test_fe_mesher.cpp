// TetGen tetrahedralisation, tissue labelling, surface checks (closedness, self-intersection).
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <map>

#include "pectus/errors.h"
#include "pectus/fe/solver.h"
#include "pectus/fe/tetgen_mesher.h"

using namespace pectus::fe;
using Eigen::Vector3d;

namespace {

// closed triangulated box surface [o, o+size], faces with centroid z < zSplit labelled 1, else 2
SurfaceMesh boxSurface(const Vector3d& o, const Vector3d& size, int nx, int ny, int nz, double zSplit) {
  const TetMesh m = structuredBox(size.x(), size.y(), size.z(), nx, ny, nz, 1);
  SurfaceMesh s;
  std::map<int, int> remap;
  for (const auto& f : boundaryFaces(m)) {
    std::array<int, 3> F;
    Vector3d c = Vector3d::Zero();
    for (int k = 0; k < 3; ++k) {
      auto it = remap.find(f.n[k]);
      if (it == remap.end()) {
        it = remap.emplace(f.n[k], static_cast<int>(s.V.size())).first;
        s.V.push_back(o + m.nodes[f.n[k]]);
      }
      F[k] = it->second;
      c += s.V[F[k]] / 3;
    }
    s.F.push_back(F);
    s.faceTissue.push_back(c.z() < zSplit ? 1 : 2);
  }
  return s;
}

SurfaceMesh merge(const SurfaceMesh& a, const SurfaceMesh& b) {
  SurfaceMesh s = a;
  const int off = static_cast<int>(a.V.size());
  s.V.insert(s.V.end(), b.V.begin(), b.V.end());
  for (auto f : b.F) s.F.push_back({f[0] + off, f[1] + off, f[2] + off});
  s.faceTissue.insert(s.faceTissue.end(), b.faceTissue.begin(), b.faceTissue.end());
  return s;
}

}  // namespace

TEST(FeMesher, BoxHasNoSelfIntersection) {
  const SurfaceMesh s = boxSurface({0, 0, 0}, {10, 10, 40}, 2, 2, 8, 20);
  EXPECT_FALSE(findSelfIntersection(s).has_value());
  EXPECT_NO_THROW(checkSurfaceForTetgen(s));
}

TEST(FeMesher, OverlappingShellsAreReportedWithAFacePair) {
  const SurfaceMesh a = boxSurface({0, 0, 0}, {10, 10, 10}, 2, 2, 2, 100);
  const SurfaceMesh b = boxSurface({5, 5, 5}, {10, 10, 10}, 2, 2, 2, 100);
  const SurfaceMesh s = merge(a, b);
  auto p = findSelfIntersection(s);
  ASSERT_TRUE(p.has_value());
  const int na = static_cast<int>(a.F.size());
  EXPECT_TRUE((p->first < na) != (p->second < na)) << p->first << " " << p->second;
  try {
    checkSurfaceForTetgen(s);
    FAIL() << "no exception";
  } catch (const pectus::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("faces " + std::to_string(p->first) + " and " + std::to_string(p->second)),
              std::string::npos) << e.what();
  }
  EXPECT_THROW(tetrahedralize(s), pectus::InputError);  // before TetGen can crash
  // disjoint shells are fine
  const SurfaceMesh c = merge(a, boxSurface({20, 0, 0}, {10, 10, 10}, 2, 2, 2, 100));
  EXPECT_FALSE(findSelfIntersection(c).has_value());
}

TEST(FeMesher, FoldedVertexIsASelfIntersection) {
  SurfaceMesh s = boxSurface({0, 0, 0}, {10, 10, 10}, 2, 2, 2, 100);
  // push the centre vertex of the top face (z = 10) through the bottom face
  int top = -1;
  for (size_t i = 0; i < s.V.size(); ++i)
    if ((s.V[i] - Vector3d(5, 5, 10)).norm() < 1e-9) top = static_cast<int>(i);
  ASSERT_GE(top, 0);
  EXPECT_FALSE(findSelfIntersection(s).has_value());
  s.V[top].z() = -3;
  EXPECT_TRUE(findSelfIntersection(s).has_value());
}

TEST(FeMesher, CollinearFaceIsNamedBeforeTetgen) {
  SurfaceMesh s = boxSurface({0, 0, 0}, {10, 10, 10}, 4, 4, 2, 100);  // the top centre's neighbours are inner points
  // move the centre vertex of the top face onto the line through two of its neighbours: its faces there
  // become collinear (zero area) without any face crossing another
  int top = -1;
  for (size_t i = 0; i < s.V.size(); ++i)
    if ((s.V[i] - Vector3d(5, 5, 10)).norm() < 1e-9) top = static_cast<int>(i);
  ASSERT_GE(top, 0);
  for (const auto& f : s.F)  // onto the midpoint of the opposite edge of one of its faces (the top stays flat)
    for (int k = 0; k < 3; ++k)
      if (f[k] == top) {
        s.V[top] = 0.5 * (s.V[f[(k + 1) % 3]] + s.V[f[(k + 2) % 3]]);
        goto moved;
      }
moved:
  const auto p = findSelfIntersection(s);
  ASSERT_TRUE(p.has_value());
  EXPECT_EQ(p->first, p->second);
  try {
    checkSurfaceForTetgen(s);
    FAIL() << "no exception";
  } catch (const pectus::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("Face " + std::to_string(p->first) + " is degenerate"), std::string::npos) << e.what();
  }
}

TEST(FeMesher, OpenSurfaceIsAnError) {
  SurfaceMesh s = boxSurface({0, 0, 0}, {10, 10, 10}, 2, 2, 2, 100);
  s.F.pop_back();
  s.faceTissue.pop_back();
  try {
    tetrahedralize(s);
    FAIL() << "no exception";
  } catch (const pectus::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not closed"), std::string::npos) << e.what();
  }
}

TEST(FeMesher, SurfaceVertexIsNodeOfTheSameIndex) {
  // TetGen drops an input point it does not mesh and numbers the rest consecutively; without renumbering,
  // node i would be another point than surface vertex i after it (an FE load or a deformed-layer vertex on
  // the wrong node)
  const SurfaceMesh box = boxSurface({0, 0, 0}, {10, 10, 10}, 2, 2, 2, 100);
  TetgenOptions o;
  o.maxVolume = 20;
  SurfaceMesh inside = box;  // a point in no face inside the volume: TetGen meshes it
  inside.V.insert(inside.V.begin() + 3, Vector3d(5, 2.5, 5));
  for (auto& f : inside.F)
    for (int& v : f) v += v >= 3;
  const TetMesh m = tetrahedralize(inside, o);
  std::vector<int> inTet(m.nodes.size(), 0);
  for (const auto& t : m.tets)
    for (int k = 0; k < 4; ++k) ++inTet[t[k]];
  for (size_t i = 0; i < inside.V.size(); ++i) {
    EXPECT_EQ((m.nodes[i] - inside.V[i]).norm(), 0.0) << "vertex " << i;
    EXPECT_GT(inTet[i], 0) << "vertex " << i;
  }
  SurfaceMesh outside = inside;  // outside the volume: TetGen drops it
  outside.V[3] = Vector3d(30, 5, 5);
  try {
    tetrahedralize(outside, o);
    FAIL() << "no throw";
  } catch (const pectus::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("surface vertex 3 "), std::string::npos) << e.what();
  }
}

TEST(FeMesher, TetgenBoxLabelsVolumeAndSeriesBar) {
  const SurfaceMesh s = boxSurface({0, 0, 0}, {10, 10, 40}, 2, 2, 8, 20);
  TetgenOptions o;
  o.radiusEdgeRatio = 1.5;
  o.maxVolume = 4.0;
  const TetMesh m = tetrahedralize(s, o);
  ASSERT_GT(m.numTets(), 1000);
  double vol = 0;
  int wrong = 0;
  for (int t = 0; t < m.numTets(); ++t) {
    ASSERT_GT(m.tetVolume(t), 0);
    EXPECT_LE(m.tetVolume(t), 4.0 + 1e-9);
    vol += m.tetVolume(t);
    const double z = (m.nodes[m.tets[t][0]] + m.nodes[m.tets[t][1]] + m.nodes[m.tets[t][2]] + m.nodes[m.tets[t][3]]).z() / 4;
    if (std::abs(z - 20) > 4 && m.tissue[t] != (z < 20 ? 1 : 2)) ++wrong;
  }
  EXPECT_NEAR(vol, 4000.0, 1e-6);
  EXPECT_EQ(wrong, 0);
  for (size_t i = 0; i < s.V.size(); ++i) EXPECT_EQ((m.nodes[i] - s.V[i]).norm(), 0.0);

  // bar in tension: bone half and a 10x softer half in series, rollers at z = 0
  o.order = 2;
  const TetMesh q = tetrahedralize(s, o);
  EXPECT_EQ(q.order, 2);
  EXPECT_EQ(q.numTets(), m.numTets());
  Problem p;
  p.mesh = &q;
  p.materials = {{1, {1000.0, 0.3}}, {2, {100.0, 0.3}}};
  std::vector<BoundaryFace> top;
  for (int i = 0; i < q.numNodes(); ++i) {
    const Vector3d& x = q.nodes[i];
    if (x.z() > 1e-9) continue;
    p.fixed.push_back({i, 2, 0.0});
    if (x.norm() < 1e-9) p.fixed.push_back({i, 0, 0.0}), p.fixed.push_back({i, 1, 0.0});
    if ((x - Vector3d(10, 0, 0)).norm() < 1e-9) p.fixed.push_back({i, 1, 0.0});
  }
  for (const auto& f : boundaryFaces(q))
    if (q.nodes[f.n[0]].z() > 40 - 1e-9 && q.nodes[f.n[1]].z() > 40 - 1e-9 && q.nodes[f.n[2]].z() > 40 - 1e-9) top.push_back(f);
  const double P = 100;
  p.force = tractionLoads(q, top, Vector3d(0, 0, P / 100));
  const Result r = solveLinear(p);
  double uz = 0;
  int n = 0;
  for (int i = 0; i < q.numNodes(); ++i)
    if (q.nodes[i].z() > 40 - 1e-9) uz += r.displacement(i).z(), ++n;
  uz /= n;
  const double exact = P / 100 * (20 / 1000.0 + 20 / 100.0);
  std::printf("[series bar] %d TET10, u_z %.5f mm, exact %.5f mm\n", q.numTets(), uz, exact);
  EXPECT_NEAR(uz / exact, 1.0, 0.03);  // the tissue interface inside is jagged (nearest-face labels)
}

// the faces of fuzz_mesh.h's smallest closed UV sphere (14 vertices: two poles, three rings of four); the
// decoder's near-duplicate-vertex edit on it gives the two fe_model corpus inputs below
const std::vector<std::array<int, 3>> kUvSphere14Faces = {
    {0, 2, 1}, {0, 3, 2}, {0, 4, 3}, {0, 1, 4}, {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6},
    {3, 4, 8}, {3, 8, 7}, {4, 1, 5}, {4, 5, 8}, {5, 6, 10}, {5, 10, 9}, {6, 7, 11}, {6, 11, 10},
    {7, 8, 12}, {7, 12, 11}, {8, 5, 9}, {8, 9, 12}, {13, 9, 10}, {13, 10, 11}, {13, 11, 12}, {13, 12, 9},
};

// Debian's TetGen keeps its assertions: on this closed, self-intersection-free sphere
// (tests/fuzz/corpus/fe_model/crash-tetgen-insertpoint-assert: two vertices 1e-6 apart at its centre,
// where the surface pinches) its quality refinement stops on assert(0) in insertpoint. TetGen runs in a
// child process, so that is an InputError here and not the end of the program (and of MeshLab).
static SurfaceMesh pinchedSphere() {
  SurfaceMesh s;
  s.V = {
      {0, 0, -1.340268611907959}, {0.76586496829986572, 0.2011294811964035, -0.8185495138168335},
      {-0.2011294811964035, 0.76586496829986572, -0.8185495138168335}, {-0.76586496829986572,
      -0.2011294811964035, -0.8185495138168335}, {-0.059666760265827179, -0.58226418495178223,
      -1.086699366569519}, {0.94918078184127808, -0.31423431634902954, -0.023699482902884483},
      {0.05971933901309967, 0.9979933500289917, -0.028206806629896164}, {-0.99547308683395386,
      0.093056224286556244, -0.025913797318935394}, {-0.05872681736946106, -0.99735629558563232,
      -0.057358786463737488}, {0.71474152803421021, 0.18770357966423035, 0.90297895669937134},
      {-1.5512948436935403e-07, 5.9070521274406929e-07, 1.0612711776047945e-06}, {-0.59070521593093872,
      -0.15512949228286743, 1.0612711906433105}, {1.5512948468576033e-25, -5.9070520880531568e-25,
      1.0612711418728368e-24}, {0, 0, 1.340268611907959},};
  s.F = kUvSphere14Faces;
  s.faceTissue.assign(s.F.size(), 1);
  return s;
}

TEST(FeMesher, TetgenAssertionIsAnErrorNotAnAbort) {
  const SurfaceMesh s = pinchedSphere();
  TetgenOptions o;
  o.radiusEdgeRatio = 1.2;
  o.maxVolume = 0.041604772732396877;
  try {
    tetrahedralize(s, o);
    FAIL() << "TetGen meshed it (this TetGen may not assert on it any more: the test then proves nothing)";
  } catch (const pectus::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("TetGen stopped on one of its internal assertions"), std::string::npos) << e.what();
    std::printf("[message] %s\n", e.what());
    // and it says where: the pinch (vertex 12 is ~1e-6 mm from the faces around vertex 10)
    EXPECT_NE(std::string(e.what()).find("smallest feature, a likely cause: vertex 1"), std::string::npos) << e.what();
  }
  // the process goes on, and meshes a valid surface afterwards
  EXPECT_GT(tetrahedralize(boxSurface({0, 0, 0}, {10, 10, 10}, 2, 2, 2, 5)).numTets(), 0);
}

// TetGen's quality refinement can go on without end: on this 14-vertex sphere
// (tests/fuzz/corpus/fe_model/timeout-tetgen-refinement) it runs for more than 9 minutes. The child is killed
// at the time limit and the call is an InputError.
TEST(FeMesher, TetgenThatDoesNotFinishIsStoppedAtTheTimeLimit) {
  SurfaceMesh s;
  s.V = {
      {0, 0, -1.340268611907959}, {0.76586496829986572, 0.2011294811964035, -0.8185495138168335},
      {-0.2011294811964035, 0.76586496829986572, -0.8185495138168335}, {-0.76586496829986572,
      -0.2011294811964035, -0.8185495138168335}, {-0.23156355321407318, -0.50754857063293457,
      -1.1123201847076416}, {0.88902926445007324, -0.40560999512672424, -0.28465315699577332},
      {0.40795162320137024, 0.89416170120239258, -0.24731607735157013}, {-0.88902926445007324,
      0.40560999512672424, -0.28465315699577332}, {-0.4080791175365448, -0.89444118738174438,
      -0.24511326849460602}, {0.76526921987533569, -0.34914582967758179, 0.72481173276901245},
      {-1.5539733055902616e-07, 5.917250973652699e-07, 1.0601795565889915e-06}, {-0.59070521593093872,
      -0.15512949228286743, 1.0612711906433105}, {1.5512948468576033e-25, -5.9070520880531568e-25,
      1.0612711418728368e-24}, {0, 0, 1.340268611907959},};
  s.F = kUvSphere14Faces;
  s.faceTissue.assign(s.F.size(), 1);
  TetgenOptions o;
  o.radiusEdgeRatio = 1.2;
  o.maxVolume = 0.034099013459653119;
  o.timeLimitSeconds = 1;
  const auto t0 = std::chrono::steady_clock::now();
  try {
    tetrahedralize(s, o);
    FAIL() << "TetGen finished (this TetGen may not loop on it any more: the test then proves nothing)";
  } catch (const pectus::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("TetGen did not finish within 1 s"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("smallest feature, a likely cause"), std::string::npos) << e.what();
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_LT(seconds, 30.0);  // stopped at the limit, not at TetGen's end
}

// maxAddedPoints (TetGen -S) bounds the mesh whatever the bounds ask: the box of TetgenBoxLabelsVolumeAndSeriesBar
// would take > 1000 tets; with at most 30 added points it keeps its vertices, at most 30 more nodes, its
// volume, and tets above the volume bound; without the cap the same call adds more than 30 points.
TEST(FeMesher, MaxAddedPointsBoundsTheMesh) {
  const SurfaceMesh s = boxSurface({0, 0, 0}, {10, 10, 40}, 2, 2, 8, 20);
  TetgenOptions o;
  o.radiusEdgeRatio = 1.5;
  o.maxVolume = 4.0;
  o.maxAddedPoints = 30;
  const TetMesh m = tetrahedralize(s, o);
  EXPECT_GE(m.numNodes(), int(s.V.size()));
  EXPECT_LE(m.numNodes(), int(s.V.size()) + 30);
  double vol = 0, largest = 0;
  for (int t = 0; t < m.numTets(); ++t) vol += m.tetVolume(t), largest = std::max(largest, m.tetVolume(t));
  EXPECT_NEAR(vol, 4000.0, 1e-6);
  EXPECT_GT(largest, 4.0);  // the bound is not reached: the cap stops the refinement
  for (size_t i = 0; i < s.V.size(); ++i) EXPECT_EQ((m.nodes[i] - s.V[i]).norm(), 0.0);
  o.maxAddedPoints = -1;
  EXPECT_GT(tetrahedralize(s, o).numNodes(), int(s.V.size()) + 30);
}

// smallestFeature: a box's is one of its edges; two boxes 1e-5 mm apart nearly touch (a vertex of one is
// 1e-5 mm from a face of the other, far below the 5 mm edges); the pinched sphere's is its pinch, where
// vertices 10 and 12 are ~1e-6 mm apart without sharing a face.
TEST(FeMesher, SmallestFeatureFindsNearTouchingSheetsAndPinches) {
  const SurfaceMesh a = boxSurface({0, 0, 0}, {10, 10, 10}, 2, 2, 2, 5);
  const SurfaceFeature fa = smallestFeature(a);
  EXPECT_NEAR(fa.medianEdge, 5.0, 1e-12);
  EXPECT_GT(fa.size, 0.5 * fa.medianEdge);

  const SurfaceMesh ab = merge(a, boxSurface({10 + 1e-5, 0, 0}, {10, 10, 10}, 2, 2, 2, 5));
  const SurfaceFeature f = smallestFeature(ab);
  EXPECT_NEAR(f.size, 1e-5, 1e-9);
  ASSERT_GE(f.face, 0);
  EXPECT_EQ(f.other, -1);
  const int nva = static_cast<int>(a.V.size()), nfa = static_cast<int>(a.F.size());
  EXPECT_NE(f.vertex < nva, f.face < nfa);  // the vertex of one box, the face of the other
  EXPECT_NEAR(std::abs(ab.V[f.vertex].x() - 10), 0.0, 1e-5 + 1e-12);

  const SurfaceFeature p = smallestFeature(pinchedSphere());
  EXPECT_LT(p.size, 1.2e-6);
  EXPECT_GT(p.medianEdge, 0.3);
  EXPECT_TRUE(p.vertex == 10 || p.vertex == 12) << p.vertex;
  EXPECT_GE(p.face, 0);
}
