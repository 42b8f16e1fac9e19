// Bench tool of the C1 surface core (driven by bench/c1_table31.py; it prints what it measures):
//   c1_bench interp <file>   scattered-data interpolation: reads "n m q", n lines "x y f", m lines "i j k",
//                            q lines "x y tri"; prints one line per query: C0, C1 thesis, C1 robust
//                            (default: global minimum curvature), C1 per-vertex quadratic fit
//   c1_bench volume          closed ellipsoid (320 faces): volume of flat, PN triangles, C1 (robust, thesis)
//   c1_bench timing [faces]  refinement k=3 of a ~100k-face torus, wall time (OpenMP threads as set)
#include <omp.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <string>

#include "pectus/c1/shapes.h"
#include "pectus/c1/surface.h"

using namespace pectus::c1;

namespace {

int interp(const char* path) {
  std::ifstream in(path);
  int n, m, q;
  if (!(in >> n >> m >> q)) { std::cerr << "bad input\n"; return 2; }
  std::vector<Vec2> xy(n);
  std::vector<double> f(n);
  for (int i = 0; i < n; ++i) in >> xy[i].x() >> xy[i].y() >> f[i];
  std::vector<std::array<int, 3>> tris(m);
  for (auto& t : tris) in >> t[0] >> t[1] >> t[2];
  const HeightInterpolant thesis(xy, f, tris, GradientMethod::InverseArea);
  const HeightInterpolant robust(xy, f, tris, GradientMethod::MinimumCurvature);
  const HeightInterpolant qfit(xy, f, tris, GradientMethod::QuadraticFit);
  for (int k = 0; k < q; ++k) {
    Vec2 p;
    int t;
    in >> p.x() >> p.y() >> t;
    // C0: linear interpolation on the same triangle
    const auto& T = tris[t];
    const Vec2 a = xy[T[0]], b = xy[T[1]], c = xy[T[2]];
    const double det = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
    const Vec2 d = p - a;
    const double s = (d.x() * (c - a).y() - d.y() * (c - a).x()) / det;
    const double tt = ((b - a).x() * d.y() - (b - a).y() * d.x()) / det;
    const double lin = (1 - s - tt) * f[T[0]] + s * f[T[1]] + tt * f[T[2]];
    std::printf("%.17g %.17g %.17g %.17g\n", lin, thesis.value(t, p), robust.value(t, p), qfit.value(t, p));
  }
  return 0;
}


// PN triangles (Vlachos et al. 2001) with the same vertex normals: same edge control points as the
// vertex-normal C1 surface, b111 = E + (E - V)/2, no blend; refined k x k like C1Surface::refine
double pnVolume(const C1Surface& s, int k) {
  const TriMesh& m = s.mesh();
  double vol = 0;
  for (int f = 0; f < int(m.F.size()); ++f) {
    const auto cn = s.controlNet(f);  // b300 b210 b201 b120 b102 b030 b021 b012 b003 ...
    const Vec3 E = (cn[1] + cn[2] + cn[3] + cn[4] + cn[6] + cn[7]) / 6, V = (cn[0] + cn[5] + cn[8]) / 3;
    const Vec3 b111 = E + (E - V) / 2;
    auto P = [&](double u, double v, double w) {
      return Vec3(u * u * u * cn[0] + 3 * u * u * v * cn[1] + 3 * u * u * w * cn[2] + 3 * u * v * v * cn[3] +
                  3 * u * w * w * cn[4] + v * v * v * cn[5] + 3 * v * v * w * cn[6] + 3 * v * w * w * cn[7] +
                  w * w * w * cn[8] + 6 * u * v * w * b111);
    };
    for (int j = 0; j < k; ++j)
      for (int i = 0; i < k - j; ++i) {
        auto g = [&](int a, int b) { return P(double(k - a - b) / k, double(a) / k, double(b) / k); };
        vol += g(i, j).dot(g(i + 1, j).cross(g(i, j + 1)));
        if (i + j < k - 1) vol += g(i + 1, j).dot(g(i + 1, j + 1).cross(g(i, j + 1)));
      }
  }
  return vol / 6;
}

int volume() {
  const Vec3 axes(1.0, 0.8, 0.6);
  const TriMesh m = icoEllipsoid(2, axes);
  const double exact = 4.0 / 3.0 * M_PI * axes.prod();
  const int k = 16;
  Options thesisOpt;
  thesisOpt.gradient = GradientMethod::InverseArea;
  const C1Surface robust(m), thesis(m, thesisOpt);
  // exact ellipsoid normals, for reference
  std::vector<Vec3> en;
  for (const auto& v : m.V) en.push_back(Vec3(v.x() / (axes.x() * axes.x()), v.y() / (axes.y() * axes.y()), v.z() / (axes.z() * axes.z())).normalized());
  const C1Surface exactN(m, en, Options());
  auto rel = [&](double v) { return 100.0 * (v - exact) / exact; };
  std::printf("ellipsoid semi-axes (1, 0.8, 0.6), %zu faces, exact volume %.6f; curved surfaces measured on a %dx%d refinement\n",
              m.F.size(), exact, k, k);
  std::printf("%-44s %12s %10s\n", "surface", "volume", "error %");
  std::printf("%-44s %12.6f %+10.4f\n", "flat mesh (C0)", enclosedVolume(m), rel(enclosedVolume(m)));
  std::printf("%-44s %12.6f %+10.4f\n", "PN triangles (robust normals)", pnVolume(robust, k), rel(pnVolume(robust, k)));
  std::printf("%-44s %12.6f %+10.4f\n", "C1 Goodman-Said, robust normals (default)", enclosedVolume(robust.refine(k)),
              rel(enclosedVolume(robust.refine(k))));
  std::printf("%-44s %12.6f %+10.4f\n", "C1 Goodman-Said, thesis inverse-area normals", enclosedVolume(thesis.refine(k)),
              rel(enclosedVolume(thesis.refine(k))));
  std::printf("%-44s %12.6f %+10.4f\n", "PN triangles (exact normals)", pnVolume(exactN, k), rel(pnVolume(exactN, k)));
  std::printf("%-44s %12.6f %+10.4f\n", "C1 Goodman-Said (exact normals)", enclosedVolume(exactN.refine(k)),
              rel(enclosedVolume(exactN.refine(k))));
  return 0;
}

int timing(int faces) {
  // torus grid n x m x 2 faces
  const int n = int(std::sqrt(faces / 2.0 * 2)), mm = std::max(3, faces / (2 * n));
  TriMesh t;
  for (int j = 0; j < mm; ++j)
    for (int i = 0; i < n; ++i) {
      const double a = 2 * M_PI * i / n, b = 2 * M_PI * j / mm;
      t.V.push_back(Vec3((2 + 0.7 * std::cos(b)) * std::cos(a), (2 + 0.7 * std::cos(b)) * std::sin(a), 0.7 * std::sin(b)));
    }
  for (int j = 0; j < mm; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * n + i, b = j * n + (i + 1) % n, c = ((j + 1) % mm) * n + (i + 1) % n, d = ((j + 1) % mm) * n + i;
      t.F.push_back({a, b, c});
      t.F.push_back({a, c, d});
    }
  using clk = std::chrono::steady_clock;
  double best = 1e9, bestBuild = 0, bestRefine = 0;
  std::size_t outF = 0;
  for (int rep = 0; rep < 3; ++rep) {
    const auto t0 = clk::now();
    const C1Surface s(t);
    const auto t1 = clk::now();
    std::vector<Vec3> nrm;
    const TriMesh r = s.refine(3, &nrm);
    const auto t2 = clk::now();
    outF = r.F.size();
    const double tb = std::chrono::duration<double>(t1 - t0).count(), tr = std::chrono::duration<double>(t2 - t1).count();
    if (tb + tr < best) { best = tb + tr; bestBuild = tb; bestRefine = tr; }
  }
  std::printf("refine k=3: %zu faces -> %zu faces, %d OpenMP threads: build %.3f s + refine %.3f s = %.3f s (best of 3)\n",
              t.F.size(), outF, omp_get_max_threads(), bestBuild, bestRefine, best);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string cmd = argc > 1 ? argv[1] : "";
  if (cmd == "interp" && argc > 2) return interp(argv[2]);
  if (cmd == "volume") return volume();
  if (cmd == "timing") return timing(argc > 2 ? std::atoi(argv[2]) : 100000);
  std::fprintf(stderr, "usage: c1_bench interp <file> | volume | timing [faces]\n");
  return 2;
}
