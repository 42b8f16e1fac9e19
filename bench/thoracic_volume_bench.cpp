// Benchmark of the thoracic volume methods on a ~300k-face analytic cage (ellipsoid sheets cut
// into tilted rib bands, exact volumes known), with CGAL 5.5's alpha_wrap_3 envelope as the peer of
// the Ferguson envelope in the same run. Prints a table: method, volume, error vs exact, time.
//   bench_thoracic_volume [nth nz]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "../common/tests/analytic_cages.h"
#include "pectus/vol/thoracic_volume.h"

#ifdef PECTUS_HAVE_CGAL
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/clip.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/alpha_wrap_3.h>
#endif

using namespace pectus::vol;
using namespace pectus::vol::testing;

namespace {
double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }
void row(const char* method, double v, double exact, double t, const char* note = "") {
  std::printf("%-34s %14.3f %14.3f %+9.3f %% %9.3f s  %s\n", method, v / 1000, exact / 1000, 100 * (v - exact) / exact, t, note);
}
}  // namespace

int main(int argc, char** argv) {
  const int nth = argc > 2 ? std::atoi(argv[1]) : 512, nz = argc > 2 ? std::atoi(argv[2]) : 224;
  const double a = 120, b = 85, c = 150, t = 8, zcut = 130, z0 = -110, z1 = 110;
  const Soup cage = bandedEllipsoid(a, b, c, t, zcut, nth, nz);
  const double inner = ellipsoidSegmentVolume(a, b, c, z0, z1), outer = ellipsoidSegmentVolume(a + t, b + t, c + t, z0, z1);
  std::printf("cage: %zu vertices, %zu faces (banded ellipsoid %g x %g x %g mm, ribs %g mm thick), range z = %g .. %g mm\n",
              cage.V.size(), cage.F.size(), a, b, c, t, z0, z1);
  std::printf("%-34s %14s %14s %11s %11s\n", "method", "volume cm3", "exact cm3", "error", "time");

  double t0 = now();
  const auto s = sliceVolume(cage, {z0, z1}, SliceParams{});
  row("slice method (2.6 mm, 512^2)", s.volume, inner, now() - t0, "exact: inner sheet");

  t0 = now();
  const auto e = fergusonEnvelope(cage, {z0, z1}, EnvelopeParams{});
  char note[160];
  std::snprintf(note, sizeof note, "exact: outer sheet; %d samples, %d moves, %d ray solves", e.samples, e.moves, e.cutTests);
  row("Ferguson envelope 16x16", e.volume, outer, now() - t0, note);

#ifdef PECTUS_HAVE_CGAL
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Mesh = CGAL::Surface_mesh<K::Point_3>;
  std::vector<K::Point_3> pts;
  pts.reserve(cage.V.size());
  for (const auto& p : cage.V) pts.emplace_back(p.x(), p.y(), p.z());
  std::vector<std::array<std::size_t, 3>> tris;
  tris.reserve(cage.F.size());
  for (const auto& f : cage.F) tris.push_back({std::size_t(f[0]), std::size_t(f[1]), std::size_t(f[2])});
  for (double alpha : {60.0, 130.0}) {
    const double offset = 0.5;
    t0 = now();
    Mesh wrap;
    CGAL::alpha_wrap_3(pts, tris, alpha, offset, wrap);
    const double tw = now() - t0;
    // the measured range: clip at z0 and z1 (closed clips)
    namespace PMP = CGAL::Polygon_mesh_processing;
    PMP::clip(wrap, K::Plane_3(0, 0, 1, -z1), CGAL::parameters::clip_volume(true));
    PMP::clip(wrap, K::Plane_3(0, 0, -1, z0), CGAL::parameters::clip_volume(true));
    const double v = PMP::volume(wrap);
    const double tt = now() - t0;
    std::snprintf(note, sizeof note, "exact: outer sheet; wrap %.3f s + clip/volume; %zu faces, offset %.1f mm", tw,
                  std::size_t(wrap.number_of_faces()), offset);
    char name[64];
    std::snprintf(name, sizeof name, "CGAL alpha_wrap_3 (alpha %g mm)", alpha);
    row(name, v, outer, tt, note);
  }
#else
  std::printf("CGAL not found at configure time: install libcgal-dev for the alpha_wrap_3 peer\n");
#endif
  return 0;
}
