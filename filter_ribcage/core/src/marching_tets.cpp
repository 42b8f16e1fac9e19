#include "pectus/ribcage/marching_tets.h"

#include <algorithm>
#include <cmath>

namespace pectus::ribcage {

namespace {
// Kuhn tetrahedra of the unit cube: path 000 -> e_p1 -> e_p1+e_p2 -> 111 for each axis permutation,
// listed with positive orientation (odd permutations get their last two vertices swapped).
struct Tet { int v[4]; };  // corner codes: bit0 x, bit1 y, bit2 z
constexpr int kPerm[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};

std::array<Tet, 6> kuhnTets() {
  std::array<Tet, 6> t{};
  for (int i = 0; i < 6; ++i) {
    const int c1 = 1 << kPerm[i][0], c2 = c1 | (1 << kPerm[i][1]);
    t[i] = i < 3 ? Tet{{0, c1, c2, 7}} : Tet{{0, c1, 7, c2}};
  }
  return t;
}

// even permutations putting the given vertex first / the given pair first
constexpr int kOdd[4][4] = {{0, 1, 2, 3}, {1, 0, 3, 2}, {2, 3, 0, 1}, {3, 2, 1, 0}};
// pairs (i1,i2) inside -> even ordering (i1,i2,o1,o2)
int pairOrder(int i1, int i2, int out[4]) {
  static const int table[6][4] = {{0, 1, 2, 3}, {0, 2, 3, 1}, {0, 3, 1, 2}, {1, 2, 0, 3}, {1, 3, 2, 0}, {2, 3, 0, 1}};
  int idx = -1;
  if (i1 == 0 && i2 == 1) idx = 0;
  else if (i1 == 0 && i2 == 2) idx = 1;
  else if (i1 == 0 && i2 == 3) idx = 2;
  else if (i1 == 1 && i2 == 2) idx = 3;
  else if (i1 == 1 && i2 == 3) idx = 4;
  else idx = 5;
  for (int k = 0; k < 4; ++k) out[k] = table[idx][k];
  return idx;
}
// one block's triangles (corner keys) and the vertices on its cells' edges (key: the edge's lower grid point
// index * 8 + its direction bits)
struct BlockOut {
  std::vector<std::array<std::uint64_t, 3>> tris;
  std::vector<std::pair<std::uint64_t, Eigen::Vector3d>> verts;
};

// the field at the block's sx x sy x sz grid points from (i0, j0, k0), x fastest; values within eps of zero
// are pushed off it, keeping their sign
std::vector<double> sampleBlock(const SparseGrid& g, const std::function<double(const Eigen::Vector3d&)>& f, int i0,
                                int j0, int k0, int sx, int sy, int sz, double eps) {
  std::vector<double> val(std::size_t(sx) * sy * sz);
  for (int k = 0; k < sz; ++k)
    for (int j = 0; j < sy; ++j)
      for (int i = 0; i < sx; ++i) {
        const Eigen::Vector3d p = g.origin + g.h * Eigen::Vector3d(i0 + i, j0 + j, k0 + k);
        double v = f(p);
        if (v >= 0 && v < eps) v = eps;
        else if (v < 0 && v > -eps) v = -eps;
        val[(std::size_t(k) * sy + j) * sx + i] = v;
      }
  return val;
}

// the triangles of the cube at grid point (gi, gj, gk) with corner values cv, by its Kuhn tets; a vertex
// on a sign-changing edge is interpolated linearly
void marchCube(const SparseGrid& g, const std::array<Tet, 6>& tets, const double cv[8], long long gi, long long gj,
               long long gk, BlockOut& o) {
  const long long nx = g.points[0], ny = g.points[1];
  auto key = [&](int ca, int cb) -> std::uint64_t {
    if (cb < ca) std::swap(ca, cb);  // ca is a subset of cb (monotone Kuhn path)
    const long long pi = gi + (ca & 1), pj = gj + ((ca >> 1) & 1), pk = gk + ((ca >> 2) & 1);
    const std::uint64_t idx = std::uint64_t((pk * ny + pj) * nx + pi);
    const std::uint64_t kk = idx * 8 + std::uint64_t(ca ^ cb);
    const double fa = cv[ca], fb = cv[cb];
    const double t = fa / (fa - fb);
    const Eigen::Vector3d pa = g.origin + g.h * Eigen::Vector3d(double(pi), double(pj), double(pk));
    const int d = ca ^ cb;
    o.verts.push_back({kk, pa + t * g.h * Eigen::Vector3d(d & 1, (d >> 1) & 1, (d >> 2) & 1)});
    return kk;
  };
  for (const Tet& t : tets) {
    int in[4], nin = 0;
    for (int q = 0; q < 4; ++q)
      if (cv[t.v[q]] < 0) in[nin++] = q;
    if (nin == 0 || nin == 4) continue;
    if (nin == 1 || nin == 3) {
      int odd;
      if (nin == 1) odd = in[0];
      else {
        odd = 0 + 1 + 2 + 3 - in[0] - in[1] - in[2];
      }
      const int* ord = kOdd[odd];
      const int o0 = t.v[ord[0]], x = t.v[ord[1]], y = t.v[ord[2]], z = t.v[ord[3]];
      if (nin == 1) o.tris.push_back({key(o0, x), key(o0, y), key(o0, z)});
      else o.tris.push_back({key(o0, x), key(o0, z), key(o0, y)});
    } else {
      int ord[4];
      pairOrder(in[0], in[1], ord);
      const int a = t.v[ord[0]], bq = t.v[ord[1]], c = t.v[ord[2]], d = t.v[ord[3]];
      const auto ac = key(a, c), ad = key(a, d), bd = key(bq, d), bc = key(bq, c);
      o.tris.push_back({ac, ad, bd});
      o.tris.push_back({ac, bd, bc});
    }
  }
}

// one soup of the blocks' triangles, their vertices merged by key (the blocks' vertex lists are freed)
TriSoup mergeBlocks(std::vector<BlockOut>& outs) {
  std::vector<std::pair<std::uint64_t, Eigen::Vector3d>> all;
  std::size_t nt = 0;
  for (auto& o : outs) {
    all.insert(all.end(), o.verts.begin(), o.verts.end());
    nt += o.tris.size();
    o.verts.clear();
    o.verts.shrink_to_fit();
  }
  std::sort(all.begin(), all.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  all.erase(std::unique(all.begin(), all.end(), [](const auto& x, const auto& y) { return x.first == y.first; }),
            all.end());
  TriSoup s;
  s.V.resize(all.size());
  std::vector<std::uint64_t> keys(all.size());
  for (std::size_t i = 0; i < all.size(); ++i) {
    keys[i] = all[i].first;
    s.V[i] = all[i].second;
  }
  s.F.reserve(nt);
  for (const auto& o : outs)
    for (const auto& t : o.tris) {
      std::array<int, 3> tri;
      for (int q = 0; q < 3; ++q)
        tri[q] = int(std::lower_bound(keys.begin(), keys.end(), t[q]) - keys.begin());
      s.F.push_back(tri);
    }
  return s;
}
}  // namespace

TriSoup marchingTets(const SparseGrid& g, const std::function<double(const Eigen::Vector3d&)>& f) {
  const auto nb = g.blocks();
  const int B = g.block;
  const auto tets = kuhnTets();
  const double eps = 1e-4 * g.h;
  const long long nBlocks = (long long)nb[0] * nb[1] * nb[2];

  std::vector<long long> act;
  for (long long b = 0; b < nBlocks; ++b)
    if (g.active[std::size_t(b)]) act.push_back(b);
  std::vector<BlockOut> outs(act.size());

  // each active block: sample the field at its points, march its cells, merge its vertices
#pragma omp parallel for schedule(dynamic, 4)
  for (long long ai = 0; ai < (long long)act.size(); ++ai) {
    const long long b = act[std::size_t(ai)];
    const int bx = int(b % nb[0]), by = int((b / nb[0]) % nb[1]), bz = int(b / ((long long)nb[0] * nb[1]));
    const int i0 = bx * B, j0 = by * B, k0 = bz * B;
    const int ci = std::min(B, g.points[0] - 1 - i0), cj = std::min(B, g.points[1] - 1 - j0),
              ck = std::min(B, g.points[2] - 1 - k0);
    if (ci <= 0 || cj <= 0 || ck <= 0) continue;
    const int sx = ci + 1, sy = cj + 1, sz = ck + 1;
    const std::vector<double> val = sampleBlock(g, f, i0, j0, k0, sx, sy, sz, eps);
    BlockOut& o = outs[std::size_t(ai)];
    auto V = [&](int i, int j, int k) { return val[(std::size_t(k) * sy + j) * sx + i]; };
    for (int k = 0; k < ck; ++k)
      for (int j = 0; j < cj; ++j)
        for (int i = 0; i < ci; ++i) {
          double cv[8];
          int inside = 0;
          for (int c = 0; c < 8; ++c) {
            cv[c] = V(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
            inside += cv[c] < 0;
          }
          if (inside == 0 || inside == 8) continue;
          marchCube(g, tets, cv, i0 + i, j0 + j, k0 + k, o);
        }
    std::sort(o.verts.begin(), o.verts.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    o.verts.erase(std::unique(o.verts.begin(), o.verts.end(),
                              [](const auto& x, const auto& y) { return x.first == y.first; }),
                  o.verts.end());
  }
  return mergeBlocks(outs);
}

}  // namespace pectus::ribcage
