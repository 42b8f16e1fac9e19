// Fuzz target: MGA / conjugate-gradient smoothing (triangles and quads) on small, possibly broken meshes.
// Properties (mga_smooth.h): finite positions stay finite, the worst element never drops below
// min(initial worst, worstGuard), and no element is folded (pectus/folds.h) that was not.
#include "fuzz_mesh.h"
#include "pectus/smooth/mga_smooth.h"
#include "pectus/errors.h"

using namespace pectus;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // (per input: at most 6 x 6 = 36 nodes, one or two sweeps of a short micro-GA: about a millisecond)
  fuzz::Input in(data, size, fuzz::limits(5, false));
  fuzz::Reader& r = in.r;
  const fuzz::Mesh& fm = in.mesh;
  smooth::Options o;
  o.method = r.u8() % 4 == 0 ? smooth::Method::ConjugateGradient : smooth::Method::MicroGA;
  o.kind = r.flag() ? ElementKind::Quads : ElementKind::Triangles;
  o.maxSweeps = r.range(1, 2);
  o.generations = r.range(1, 3);
  o.restarts = r.range(0, 1);
  o.population = r.range(3, 4);
  o.selection = static_cast<mga::Selection>(r.u8() % 2);
  o.features = r.flag() ? smooth::FeatureDetection::Creases : smooth::FeatureDetection::Angles;
  o.featureAngleDeg = r.real(0, 180);
  o.singularAngleDeg = r.real(0, 180);
  o.worstGuard = r.flag() ? 0.0 : r.real(0, 1);
  o.minPassBelow = r.flag() ? 0.0 : r.real(0, 1);
  o.minPassSweeps = r.range(0, 1);
  o.cgIterations = r.range(1, 2);
  o.seed = r.u16();
  CMeshO m;
  fuzz::toCMesh(fm, m, o.kind == ElementKind::Quads);
  std::vector<char> fixed;
  if (r.flag())
    for (std::size_t i = 0; i < m.vert.size(); ++i) fixed.push_back(char(r.u8() % 4 == 0));
  // the element search, read last so that the bytes before it mean the same whatever it is (an input that
  // ends before it reads false: every element)
  o.elementSearch = r.flag() ? smooth::ElementSearch::Guided : smooth::ElementSearch::Every;
  if (o.elementSearch == smooth::ElementSearch::Guided && r.flag()) o.elementSearch = smooth::ElementSearch::GuidedLocal;
  try {
    const auto res = smooth::smoothMesh(m, o, fixed);
    PECTUS_FUZZ_CHECK(res.positions.size() == m.vert.size());
    for (std::size_t i = 0; i < m.vert.size(); ++i)  // (a NaN vertex in no face is not checked, and stays)
      PECTUS_FUZZ_CHECK(res.positions[i].allFinite() || !toEigen(m.vert[i].cP()).allFinite());
    if (res.before.count > 0)
      PECTUS_FUZZ_CHECK(res.after.min >= std::min(res.before.min, o.worstGuard) - 1e-9);
    PECTUS_FUZZ_CHECK(res.foldsNew == 0 && res.foldsAfter <= res.foldsBefore);
  } catch (const InputError&) {
  }
  return 0;
}
