// Fuzz target: C1 surface construction (every gradient method, frame and blend), evaluation,
// closest-point projection and refinement on small, possibly broken meshes.
// Property: a surface that was built from finite vertices evaluates to finite points and normals.
#include "fuzz_mesh.h"
#include "pectus/errors.h"

using namespace pectus;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::Input in(data, size, fuzz::limits(6, true));
  fuzz::Reader& r = in.r;
  const fuzz::Mesh& fm = in.mesh;
  c1::Options opt;
  opt.gradient = static_cast<c1::GradientMethod>(r.u8() % 3);
  opt.frame = r.flag() ? c1::Frame::HeightField : c1::Frame::VertexNormal;
  opt.blend = r.u8() % 4 == 0 ? c1::Blend::PlainCubic : c1::Blend::GoodmanSaid;
  if (r.flag()) opt.axis = r.vec3(-1, 1);
  bool finite = true;
  for (const auto& p : fm.V) finite = finite && p.allFinite();
  try {
    const c1::C1Surface s(fuzz::triMesh(fm), opt);
    PECTUS_FUZZ_CHECK(finite);  // NaN/Inf input must have been rejected
    const int nf = int(s.mesh().F.size());
    for (int q = 0; q < 2 && nf > 0; ++q) {
      const int f = r.range(0, nf - 1);
      const c1::Vec3 bary = r.vec3(0, 1);
      const auto sp = s.at(f, bary.sum() > 0 ? bary : c1::Vec3(1, 0, 0));
      PECTUS_FUZZ_CHECK(sp.point.allFinite() && sp.normal.allFinite());
    }
    for (int q = 0; q < 2 && nf > 0; ++q) {
      const c1::Vec3 p = r.vec3(-3, 3);
      const auto cp = s.closestPoint(p);
      PECTUS_FUZZ_CHECK(cp.face >= 0 && cp.face < nf);
      PECTUS_FUZZ_CHECK(cp.point.allFinite() && std::isfinite(cp.distance));
    }
    std::vector<c1::Vec3> normals;
    const auto fine = s.refine(r.range(1, 2), &normals);
    PECTUS_FUZZ_CHECK(normals.size() == fine.V.size());
    for (const auto& p : fine.V) PECTUS_FUZZ_CHECK(p.allFinite());
    for (const auto& t : fine.F)
      for (int v : t) PECTUS_FUZZ_CHECK(v >= 0 && v < int(fine.V.size()));
  } catch (const InputError&) {
  }
  return 0;
}
