// Shared input decoder of the fuzz targets: bytes -> a small triangle mesh plus parameters.
//
// A raw byte soup of coordinates and indices is almost always rejected by the input checks, so the
// decoder starts from one of a few valid shapes (open grid, closed torus, closed UV sphere) whose size and
// vertex jitter come from the bytes, then applies a few edits that make it bad in the ways real meshes are
// (flipped, dropped, doubled or stray faces, welded vertices, NaN/Inf/far/near-duplicate vertices); mode
// "raw" reads coordinates and faces straight from the bytes. The fuzzer thus reaches the algorithms on
// near-valid meshes and the checks on broken ones. Reading past the end yields zeros (deterministic).
#pragma once
#include <Eigen/Core>

#include "pectus/c1/surface.h"
#include "pectus/surface_cmesh.h"

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <vector>

namespace pectus::fuzz {

class Reader {
 public:
  Reader(const std::uint8_t* data, std::size_t size) : p_(data), n_(size) {}
  std::uint8_t u8() { return i_ < n_ ? p_[i_++] : 0; }
  std::uint16_t u16() {
    const unsigned lo = u8();
    return std::uint16_t(lo | (unsigned(u8()) << 8));
  }
  /// integer in [lo, hi]
  int range(int lo, int hi) { return lo + int(u16() % unsigned(hi - lo + 1)); }
  /// real in [lo, hi] (16-bit resolution)
  double real(double lo, double hi) { return lo + (hi - lo) * (u16() / 65535.0); }
  bool flag() { return (u8() & 1) != 0; }
  /// three reals in [lo, hi], read x, y, z in that order (never read the bytes in function arguments:
  /// their order is unspecified, gcc and clang differ, and the corpus must decode alike in both builds)
  Eigen::Vector3d vec3(double lo, double hi) {
    Eigen::Vector3d v;
    for (int k = 0; k < 3; ++k) v[k] = real(lo, hi);
    return v;
  }
  bool done() const { return i_ >= n_; }

 private:
  const std::uint8_t* p_;
  std::size_t n_, i_ = 0;
};

struct Mesh {
  std::vector<Eigen::Vector3d> V;
  std::vector<std::array<int, 3>> F;
  bool grid = false;  ///< built as an open grid: faces 2k, 2k+1 are the two triangles of a quad (v0 v1 v2), (v0 v2 v3)
};

struct MeshLimits {
  int maxSide = 8;         ///< grid/torus/sphere resolution per direction
  int maxRawVertices = 24;
  int maxRawFaces = 40;
  int maxEdits = 6;
  bool badIndices = false;  ///< edits may write out-of-range / negative indices (TriMesh inputs only)
};

inline Mesh decodeMesh(Reader& r, const MeshLimits& lim = {}) {
  Mesh m;
  const int mode = r.u8() % 4;
  const double jitter = r.real(0, 0.6);  // of the spacing
  auto jit = [&] { return jitter * r.real(-0.5, 0.5); };
  if (mode == 3) {  // raw
    const int nv = r.range(0, lim.maxRawVertices), nf = r.range(0, lim.maxRawFaces);
    for (int i = 0; i < nv; ++i) m.V.push_back(r.vec3(-2, 2));
    for (int f = 0; f < nf && nv > 0; ++f) m.F.push_back({r.range(0, nv - 1), r.range(0, nv - 1), r.range(0, nv - 1)});
  } else {
    const int a = r.range(2, lim.maxSide), b = r.range(2, lim.maxSide);
    const double amp = r.real(-1, 1);  // height / radius modulation
    if (mode == 0) {  // open grid a x b cells, height field z = amp * (x^2 - y^2) + jitter
      m.grid = true;
      for (int j = 0; j <= b; ++j)
        for (int i = 0; i <= a; ++i) {
          const double x = double(i) / a - 0.5 + jit() / a, y = double(j) / b - 0.5 + jit() / b;
          m.V.emplace_back(x, y, amp * (x * x - y * y) + jit() / a);
        }
      for (int j = 0; j < b; ++j)
        for (int i = 0; i < a; ++i) {
          const int v0 = j * (a + 1) + i, v1 = v0 + 1, v2 = v1 + a + 1, v3 = v0 + a + 1;
          m.F.push_back({v0, v1, v2});
          m.F.push_back({v0, v2, v3});
        }
    } else if (mode == 1) {  // closed torus, a+1 x b+1 around (at least 3 x 3)
      const int nu = a + 1, nv = b + 1;
      const double R = 1, rr = 0.3 + 0.25 * (amp + 1) * 0.5;
      for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
          const double u = 2 * M_PI * (i + jit()) / nu, v = 2 * M_PI * (j + jit()) / nv;
          m.V.emplace_back((R + rr * std::cos(v)) * std::cos(u), (R + rr * std::cos(v)) * std::sin(u), rr * std::sin(v));
        }
      for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
          const int v0 = j * nu + i, v1 = j * nu + (i + 1) % nu, v2 = ((j + 1) % nv) * nu + (i + 1) % nu,
                    v3 = ((j + 1) % nv) * nu + i;
          m.F.push_back({v0, v1, v2});
          m.F.push_back({v0, v2, v3});
        }
    } else {  // closed UV sphere (ellipsoid), a+1 around, b rings between the poles
      const int nu = a + 1, rings = b;
      const double sz = 1 + 0.5 * amp;
      m.V.emplace_back(0, 0, -sz);
      for (int j = 1; j < rings; ++j)
        for (int i = 0; i < nu; ++i) {
          const double th = M_PI * (j + jit()) / rings, ph = 2 * M_PI * (i + jit()) / nu;
          m.V.emplace_back(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), -sz * std::cos(th));
        }
      m.V.emplace_back(0, 0, sz);
      const int top = int(m.V.size()) - 1;
      auto ring = [&](int j, int i) { return 1 + (j - 1) * nu + (i % nu); };
      for (int i = 0; i < nu; ++i) m.F.push_back({0, ring(1, i + 1), ring(1, i)});
      for (int j = 1; j + 1 < rings; ++j)
        for (int i = 0; i < nu; ++i) {
          m.F.push_back({ring(j, i), ring(j, i + 1), ring(j + 1, i + 1)});
          m.F.push_back({ring(j, i), ring(j + 1, i + 1), ring(j + 1, i)});
        }
      for (int i = 0; i < nu; ++i) m.F.push_back({top, ring(rings - 1, i), ring(rings - 1, i + 1)});
    }
  }
  // edits that make the mesh bad the ways real meshes are
  const int edits = r.range(0, lim.maxEdits);
  for (int e = 0; e < edits && !m.V.empty(); ++e) {
    const int op = r.u8() % 9;
    const int nv = int(m.V.size());
    const int v = r.range(0, nv - 1);
    const int f = m.F.empty() ? -1 : r.range(0, int(m.F.size()) - 1);
    constexpr double inf = std::numeric_limits<double>::infinity();
    switch (op) {
      case 0: if (f >= 0) std::swap(m.F[f][1], m.F[f][2]); break;                 // flipped face
      case 1: if (f >= 0) m.F.erase(m.F.begin() + f); break;                       // hole
      case 2: if (f >= 0) m.F.push_back(m.F[f]); break;                            // doubled face
      case 3: m.F.push_back({v, r.range(0, nv - 1), r.range(0, nv - 1)}); break;   // stray face
      case 4: {                                                                    // weld v into w
        const int w = r.range(0, nv - 1);
        for (auto& F : m.F)
          for (int& i : F)
            if (i == v) i = w;
        break;
      }
      case 5: {  // near duplicate
        const int w = r.range(0, nv - 1);
        m.V[v] = m.V[w] + Eigen::Vector3d::Constant(r.real(-1e-7, 1e-7));
        break;
      }
      case 6: m.V[v] *= r.flag() ? 1e6 : 1e-6; break;                              // far / collapsed
      case 7: {
        const int k = r.range(0, 2);
        m.V[v][k] = r.flag() ? std::numeric_limits<double>::quiet_NaN() : inf;
        break;
      }
      case 8:
        if (f >= 0 && lim.badIndices) {
          const int k = r.range(0, 2);
          const bool negative = r.flag();
          m.F[f][k] = negative ? -1 - r.range(0, 3) : nv + r.range(0, 3);
        }
        break;
    }
  }
  return m;
}

inline MeshLimits limits(int maxSide, bool badIndices) {
  MeshLimits l;
  l.maxSide = maxSide;
  l.badIndices = badIndices;
  return l;
}

/// What every target starts with: the reader over its input and the mesh decoded from the first bytes.
struct Input {
  Reader r;
  Mesh mesh;
  Input(const std::uint8_t* data, std::size_t size, const MeshLimits& lim) : r(data, size), mesh(decodeMesh(r, lim)) {}
};

inline c1::TriMesh triMesh(const Mesh& m) { return {m.V, m.F}; }

/// The mesh as MeshLab holds it (indices must be valid: CMeshO stores pointers); `quads`: a grid's cell
/// pairs become quads (shared diagonal faux in both triangles, as MeshLab's OFF importer sets it).
inline void toCMesh(const Mesh& m, CMeshO& cm, bool quads) {
  pectus::toMesh(triMesh(m), cm);
  if (quads && m.grid)
    for (std::size_t f = 0; f + 1 < cm.face.size(); f += 2) {
      cm.face[f].SetF(2);      // (v0 v1 v2): edge v2-v0
      cm.face[f + 1].SetF(0);  // (v0 v2 v3): edge v0-v2
    }
}

/// Crashes (so the fuzzer reports it) when a property the code documents does not hold.
#define PECTUS_FUZZ_CHECK(cond) \
  do {                          \
    if (!(cond)) {              \
      std::fprintf(stderr, "fuzz check failed: %s (%s:%d)\n", #cond, __FILE__, __LINE__); \
      __builtin_trap();         \
    }                           \
  } while (0)

}  // namespace pectus::fuzz
