// Fuzz target: triangle-to-quad conversion (greedy / optimal pairing, quad-dominant / all-quads with the
// C1 split), the structure operators (swap, eliminate, divide) and the PolyMesh <-> CMeshO exchange.
// Properties: every element of every output mesh has valid, distinct vertex indices; positions are finite.
#include <memory>

#include "fuzz_mesh.h"
#include "pectus/errors.h"
#include "pectus/quad/quad_convert.h"
#include "pectus/quad/structure.h"

using namespace pectus;

namespace {
void checkPoly(const quad::PolyMesh& p) {
  for (const auto& v : p.V) PECTUS_FUZZ_CHECK(v.allFinite());
  for (const auto& e : p.F) {
    PECTUS_FUZZ_CHECK(e.nv == 3 || e.nv == 4);
    for (int k = 0; k < e.nv; ++k) {
      PECTUS_FUZZ_CHECK(e.v[k] >= 0 && e.v[k] < int(p.V.size()));
      for (int l = 0; l < k; ++l) PECTUS_FUZZ_CHECK(e.v[k] != e.v[l]);
    }
  }
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // (per input: at most 5 x 5 = 25 vertices; the C1 split projects every new node with the global
  // closestPoint, the costly part, so it is drawn for one input in four)
  fuzz::Input in(data, size, fuzz::limits(4, true));
  fuzz::Reader& r = in.r;
  const fuzz::Mesh& fm = in.mesh;
  quad::ConvertOptions co;
  co.pairing = r.flag() ? quad::Pairing::Greedy : quad::Pairing::Optimal;
  co.leftovers = r.u8() % 4 != 0 ? quad::Leftovers::QuadDominant : quad::Leftovers::AllQuads;
  co.minQuality = r.real(0, 0.9);
  co.maxDihedralDeg = r.real(0, 180);
  quad::StructureOptions so;
  so.swap = r.flag();
  so.eliminate = r.flag();
  so.divide = r.flag();
  so.longEdgeFactor = r.real(0.5, 3);
  so.maxDihedralDeg = r.real(0, 90);
  so.maxPasses = r.range(1, 3);
  const bool onSurface = r.u8() % 4 == 0, structureOfTriangles = r.flag();
  const auto tri = fuzz::triMesh(fm);
  try {
    const auto conv = quad::convertToQuads(tri, co);
    checkPoly(conv.mesh);
    std::unique_ptr<c1::C1Surface> surface;
    if (onSurface) {
      try {
        surface = std::make_unique<c1::C1Surface>(tri);
      } catch (const InputError&) {
      }
    }
    quad::PolyMesh in = conv.mesh;
    if (structureOfTriangles) {  // the operators in triangle mode
      in.V = tri.V;
      in.F.clear();
      for (const auto& t : tri.F) in.F.push_back({3, {t[0], t[1], t[2], -1}});
    }
    const auto st = quad::improveStructure(in, surface.get(), so);
    checkPoly(st.mesh);
    bool finite = true;
    for (const auto& v : st.mesh.V) finite = finite && v.allFinite();
    if (finite) {  // what the adapter does with the result: into MeshLab's mesh and back
      CMeshO m;
      quad::toCMesh(st.mesh, m);
      const auto back = quad::fromCMesh(m, true);
      checkPoly(back);
      PECTUS_FUZZ_CHECK(back.F.size() == st.mesh.F.size());
    }
  } catch (const InputError&) {
  }
  return 0;
}
