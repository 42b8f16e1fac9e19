// Fuzz target: thoracic volume cores - slice method, Ferguson envelope, pectus index, divergence volume -
// on small, possibly broken meshes scaled to a chest's size (mm) with a measured range from the bytes.
// Properties: results are finite and non-negative where they are volumes/areas.
#include <algorithm>

#include "fuzz_mesh.h"
#include "pectus/errors.h"
#include "pectus/vol/thoracic_volume.h"

using namespace pectus;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::Input in(data, size, fuzz::limits(6, false));
  fuzz::Reader& r = in.r;
  fuzz::Mesh& fm = in.mesh;
  const Eigen::Vector3d scale = r.vec3(10, 200).cwiseProduct(Eigen::Vector3d(1, 1, 1.5));
  for (auto& p : fm.V) p = p.cwiseProduct(scale);
  CMeshO m;
  fuzz::toCMesh(fm, m, false);
  const int what = r.u8() % 4;
  try {
    const vol::Soup s = vol::soupFromMesh(m, "fuzz");
    (void)vol::divergenceVolume(s);
    double zmin = 1e300, zmax = -1e300;
    for (const auto& p : s.V) zmin = std::min(zmin, p.z()), zmax = std::max(zmax, p.z());
    const double a = r.real(-0.2, 1.2), b = r.real(-0.2, 1.2);
    vol::Range range{zmin + std::min(a, b) * (zmax - zmin), zmin + std::max(a, b) * (zmax - zmin)};
    if (what == 0) {
      vol::SliceParams p;
      // at most ~24 planes, small rasters (finer is legal, only slower: the code paths are the same)
      p.spacing = std::max(r.real(0.5, 40), (range.zHi - range.zLo) / 24);
      p.resolution = r.range(8, 32);
      p.rays = r.range(8, 32);
      vol::requireRange(range, "fuzz");
      const auto res = vol::sliceVolume(s, range, p);
      PECTUS_FUZZ_CHECK(std::isfinite(res.volume) && res.volume >= 0);
      PECTUS_FUZZ_CHECK(std::isfinite(res.polygonVolume) && res.polygonVolume >= 0);
    } else if (what == 1) {
      vol::EnvelopeParams p;
      p.nLong = r.range(0, 5);
      p.mAround = r.range(2, 8);
      p.initialStep = r.flag() ? 0.0 : r.real(0, 50);
      // keep the run short: the step halves down to this (0.05 mm by default), and every level moves each key
      // point inwards in steps from the envelope's start: at least 1/64 of the box keeps a level to ~100
      // sweeps (an input at 1/400 takes 2.9 s in Release, over the 30 s timeout under ASan)
      Eigen::AlignedBox3d box;
      for (const auto& v : s.V) box.extend(v);
      p.minStep = std::max(r.real(0.5, 8), box.sizes().head<2>().maxCoeff() / 64);
      p.smoothing = r.flag();
      if (r.flag()) p.sternumEnd = r.vec3(-100, 100) + Eigen::Vector3d(0, 0, 100);
      p.binsPerPatch = r.range(1, 4);
      p.tessellation = r.range(1, 4);
      vol::requireRange(range, "fuzz");
      const auto res = vol::fergusonEnvelope(s, range, p);
      PECTUS_FUZZ_CHECK(std::isfinite(res.volume));
      const auto t = res.env.tessellate(p.tessellation);
      for (const auto& v : t.V) PECTUS_FUZZ_CHECK(v.allFinite());
      for (const auto& f : t.F)
        for (int k : f) PECTUS_FUZZ_CHECK(k >= 0 && k < int(t.V.size()));
    } else if (what == 2) {
      vol::IndexInputs in;
      if (r.flag()) in.level = range.zLo;
      if (r.flag()) in.midlineX = r.real(-100, 100);
      if (r.flag()) in.spineY = r.real(-100, 100);
      in.searchRange = range;
      in.searchSpacing = std::max(r.real(1, 60), (range.zHi - range.zLo) / 16);
      in.rays = r.range(16, 40);
      const auto pi = vol::pectusIndex(s, in);
      PECTUS_FUZZ_CHECK(std::isfinite(pi.transverse) && std::isfinite(pi.apMin) && std::isfinite(pi.apMax));
    } else {
      std::vector<double> zs;
      for (int k = r.range(1, 4); k > 0; --k) zs.push_back(zmin + r.real(-0.1, 1.1) * (zmax - zmin));
      const auto cuts = vol::cutPlanes(s, zs);
      PECTUS_FUZZ_CHECK(cuts.size() == zs.size());
      std::optional<Eigen::Vector2d> seed;
      if (r.flag()) seed = r.vec3(-100, 100).head<2>();
      const auto reg = vol::regionFromSegments(zs[0], cuts[0], r.range(3, 64), seed);
      const double area = reg.polygonArea();
      PECTUS_FUZZ_CHECK(std::isfinite(area));
    }
  } catch (const InputError&) {
  }
  return 0;
}
