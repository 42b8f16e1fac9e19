// Crease detection (creases.h): a noisy sphere has no crease, a noisy cube has its 12 edges, a fandisk-like
// part (a box with a bevelled edge and a cylindrical face) has its creases and nothing on the smooth face.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

#include "pectus/smooth/creases.h"
#include "pectus/smooth/mga_smooth.h"
#include "pectus/c1/surface.h"
#include "pectus/surface_cmesh.h"

using pectus::Vec3;
namespace sm = pectus::smooth;

namespace {

struct Tri {
  std::vector<Vec3> V;
  std::vector<std::array<int, 3>> F;
};

/// the unit sphere: an icosahedron subdivided `levels` times, every node moved along its normal by
/// +-noise (uniform) times the mean edge length
Tri noisySphere(int levels, double noise, unsigned seed) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  Tri m;
  for (auto p : {Vec3(-1, t, 0), Vec3(1, t, 0), Vec3(-1, -t, 0), Vec3(1, -t, 0), Vec3(0, -1, t), Vec3(0, 1, t),
                 Vec3(0, -1, -t), Vec3(0, 1, -t), Vec3(t, 0, -1), Vec3(t, 0, 1), Vec3(-t, 0, -1), Vec3(-t, 0, 1)})
    m.V.push_back(p.normalized());
  m.F = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
         {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8}, {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto k = std::minmax(a, b);
      auto it = mid.find(k);
      if (it != mid.end()) return it->second;
      m.V.push_back((m.V[std::size_t(a)] + m.V[std::size_t(b)]).normalized());
      return mid[k] = int(m.V.size()) - 1;
    };
    std::vector<std::array<int, 3>> F;
    for (const auto& f : m.F) {
      const int ab = midpoint(f[0], f[1]), bc = midpoint(f[1], f[2]), ca = midpoint(f[2], f[0]);
      F.push_back({f[0], ab, ca});
      F.push_back({f[1], bc, ab});
      F.push_back({f[2], ca, bc});
      F.push_back({ab, bc, ca});
    }
    m.F = F;
  }
  const double h = 4 * M_PI / std::sqrt(double(m.F.size()) * std::sqrt(3.0));  // ~ mean edge length
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-noise, noise);
  for (auto& p : m.V) p *= 1 + u(rng) * h;
  return m;
}

/// the cube [0, 1]^3, n x n squares per face (two triangles each, diagonals alternating), every node
/// moved by +-noise times the square size in each coordinate
Tri noisyCube(int n, double noise, unsigned seed) {
  Tri m;
  std::map<std::array<long, 3>, int> index;
  auto node = [&](const Vec3& p) {
    const std::array<long, 3> k{std::lround(p.x() * n), std::lround(p.y() * n), std::lround(p.z() * n)};
    auto it = index.find(k);
    if (it != index.end()) return it->second;
    m.V.push_back(p);
    return index[k] = int(m.V.size()) - 1;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          auto at = [&](int a, int b) {
            Vec3 p;
            p[axis] = side;
            p[(axis + 1) % 3] = double(a) / n;
            p[(axis + 2) % 3] = double(b) / n;
            return node(p);
          };
          int q[4] = {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)};
          if (side == 0) std::swap(q[1], q[3]);  // outward normals
          if ((i + j) % 2) {
            m.F.push_back({q[0], q[1], q[2]});
            m.F.push_back({q[0], q[2], q[3]});
          } else {
            m.F.push_back({q[0], q[1], q[3]});
            m.F.push_back({q[1], q[2], q[3]});
          }
        }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-noise / n, noise / n);
  for (auto& p : m.V) {
    const double dz = u(rng), dy = u(rng), dx = u(rng);
    p += Vec3(dx, dy, dz);
  }
  return m;
}

/// fandisk-like: the box [0, 2] x [0, 1] x [0, 1] whose top face is cut by a shallow cylindrical bump
/// along x (z = 1 + 0.15 cos(pi (y - 0.5)) - 0.15 cos(pi/2)... a smooth face) meeting the sides at creases,
/// and whose x = 2 end is bevelled at 45 degrees: creases of about 90, 45 and 20 degrees
Tri fandiskLike(int n) {
  // a height field over the rectangle, closed by the box's sides: built as a cube deformed
  Tri m = noisyCube(n, 0, 1);
  for (auto& p : m.V) {
    const double y = p.y(), x = p.x(), z = p.z();
    const double top = 1 + 0.25 * std::sin(M_PI * y);  // a smooth arch across, creases at y = 0 and 1
    double nz = z * top;
    double nx = 2 * x;
    // bevel: cut the x = 2, z = top corner at 45 degrees (the top's last 0.25 in x slopes down)
    if (nx > 1.75 && z > 0.5) nz -= (nx - 1.75) * (z - 0.5) / 0.5;
    p = Vec3(nx, y, nz);
  }
  return m;
}

}  // namespace

TEST(Creases, NoisySphereHasNone) {
  const Tri s = noisySphere(4, 0.15, 3);  // 2562 nodes
  const sm::Creases c = sm::detectCreases(s.V, s.F);
  EXPECT_GT(c.sharpEdges, 0u) << "the noise makes some edges sharp";
  EXPECT_EQ(c.chains.size(), 0u) << c.summary();
  EXPECT_EQ(c.creaseNodes(), 0u);
  EXPECT_NE(c.summary().find("no crease"), std::string::npos) << c.summary();
}

TEST(Creases, NoisyCubeHasTwelveChains) {
  const int n = 12;
  const Tri cube = noisyCube(n, 0.08, 5);
  const sm::Creases c = sm::detectCreases(cube.V, cube.F);
  EXPECT_EQ(c.chains.size(), 12u) << c.summary();
  for (const auto& ch : c.chains) EXPECT_EQ(ch.size(), std::size_t(n)) << c.summary();
  EXPECT_EQ(c.cornerNodes(), 8u) << c.summary();
  // every crease node on a cube edge (two coordinates at 0 or 1, within the noise)
  for (std::size_t v = 0; v < cube.V.size(); ++v) {
    int atSide = 0;
    for (int k = 0; k < 3; ++k) atSide += std::min(std::abs(cube.V[v][k]), std::abs(cube.V[v][k] - 1)) < 0.1 / n;
    EXPECT_EQ(bool(c.node[v]), atSide >= 2) << "node " << v;
  }
}

TEST(Creases, FandiskLikeFindsItsCreasesNotTheArch) {
  const int n = 16;
  const Tri f = fandiskLike(n);
  const sm::Creases c = sm::detectCreases(f.V, f.F);
  // noise-free: every sharp edge is on a crease (the box's edges, the arch's ends, the bevel's edges)
  EXPECT_GT(c.sharpEdges, 0u);
  EXPECT_EQ(c.creaseEdges, c.sharpEdges) << c.summary();
  EXPECT_GE(c.chains.size(), 9u) << c.summary();
  std::size_t onArch = 0, edgesMissed = 0;
  for (std::size_t v = 0; v < f.V.size(); ++v) {
    const Vec3& p = f.V[v];
    const bool inside = p.y() > 1e-9 && p.y() < 1 - 1e-9 && p.x() > 1e-9 && p.x() < 1.75 - 1e-9;
    const bool top = p.z() > 0.99;
    if (inside && top) onArch += c.node[v];
    // the long top edges (y = 0 and y = 1 at the top, before the bevel)
    if ((p.y() < 1e-9 || p.y() > 1 - 1e-9) && top && p.x() < 1.75) edgesMissed += !c.node[v];
  }
  EXPECT_EQ(onArch, 0u) << "no crease on the smooth arch: " << c.summary();
  EXPECT_EQ(edgesMissed, 0u) << c.summary();
}

TEST(Creases, AllCreasesAndDegenerateInputsAreDefined) {
  // the 8-node cube: every node a corner of three crease chains of one edge each
  Tri cube = noisyCube(1, 0, 1);
  sm::Creases c = sm::detectCreases(cube.V, cube.F);
  EXPECT_EQ(c.chains.size(), 12u) << c.summary();
  EXPECT_EQ(c.creaseNodes(), 8u);
  EXPECT_EQ(c.cornerNodes(), 8u);
  // nothing at all, and one triangle (boundary edges only)
  c = sm::detectCreases({}, {});
  EXPECT_EQ(c.chains.size(), 0u);
  c = sm::detectCreases({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)}, {{0, 1, 2}});
  EXPECT_EQ(c.sharpEdges, 0u);
  EXPECT_NE(c.summary().find("no crease"), std::string::npos);
}

TEST(Creases, SmoothingKeepsCreaseNodesAndRefusesAllCreases) {
  // smoothing with the crease default: the cube's crease nodes stay, others move
  const Tri cube = noisyCube(8, 0.08, 7);
  pectus::c1::TriMesh t;
  t.V = cube.V;
  t.F = cube.F;
  CMeshO m;
  pectus::toMesh(t, m);
  sm::Options o;
  o.maxSweeps = 2;
  const sm::Result r = sm::smoothMesh(m, o);
  const sm::Creases c = sm::detectCreases(cube.V, cube.F);
  EXPECT_EQ(r.creaseChains, 12u) << r.featureSummary;
  EXPECT_EQ(r.featureNodes + r.singularNodes, c.creaseNodes());
  EXPECT_EQ(r.singularNodes, 8u);
  std::size_t creaseMoved = 0, moved = 0;
  for (std::size_t v = 0; v < cube.V.size(); ++v) {
    const auto& p = m.vert[v].cP();  // the input as the mesh holds it (MESHLAB_SCALAR)
    const bool mv = (r.positions[v] - Vec3(p[0], p[1], p[2])).norm() > 0;
    (c.node[v] ? creaseMoved : moved) += mv;
  }
  EXPECT_EQ(creaseMoved, 0u);
  EXPECT_GT(moved, 100u);
  EXPECT_GT(r.after.mean, r.before.mean);
  // the 8-node cube: every node on a crease, refused with the detector's finding in the message
  const Tri c8 = noisyCube(1, 0, 1);
  t.V = c8.V;
  t.F = c8.F;
  CMeshO m8;
  pectus::toMesh(t, m8);
  try {
    sm::smoothMesh(m8, o);
    FAIL() << "a mesh that is all creases has no free node";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("12 crease chains"), std::string::npos) << e.what();
  }
}
