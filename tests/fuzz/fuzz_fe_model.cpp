// Fuzz target: the Nuss FE model builder up to (not including) the solve - labelled CMeshO -> cageFromMesh
// (weld, labels) -> surface checks (closed, self-intersection) -> TetGen -> TET10 -> boundary faces - on
// small, possibly broken closed meshes.
// Properties: every tet has valid, distinct nodes, a tissue label and positive volume; the input vertices
// keep their indices and are in a tet; the surface's smallest feature (named when TetGen fails) is valid.
// TetGen may add at most kAddedPoints points per input (TetgenOptions::maxAddedPoints): the bytes' most
// demanding bounds (radius-edge 1.2, tets of 0.004 of the box) make 5,000-26,000 tets in 0.3-5 s, which holds
// a campaign to 12-30 inputs/s, all of it in TetGen's refinement and not in this project's code. The
// regression replay (ctest fuzz_replay_fe_model) sets PECTUS_FUZZ_FULL_TETGEN=1 and meshes without the cap,
// so the corpus inputs that need full refinement (TetGen's assertion, its endless refinement, a flat tet)
// replay as the filter meshes them.
#include "fuzz_mesh.h"
#include "pectus/nuss/nuss_analysis.h"
#include "pectus/errors.h"

#include <cstdlib>

using namespace pectus;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // (per input: at most 5 x 5 = 25 vertices and a few hundred tets)
  fuzz::Input in(data, size, fuzz::limits(4, false));
  fuzz::Reader& r = in.r;
  const fuzz::Mesh& fm = in.mesh;
  OwnedMesh m;  // frees the face labels' attributes
  fuzz::toCMesh(fm, m, false);
  if (r.u8() % 8 != 0) {  // else: no labels
    std::vector<int> tissue, part;
    for (std::size_t f = 0; f < m.face.size(); ++f) {
      tissue.push_back(r.range(1, 3));
      const bool rib = r.range(0, 3) != 0;
      const int side = r.range(0, 1);
      part.push_back(rib ? ribPart(side, r.range(1, 12)) : 0);
    }
    writeFaceLabels(m, tissue, part);
  }
  fe::TetgenOptions to;
  to.radiusEdgeRatio = r.flag() ? 0.0 : r.real(1.2, 3);
  const double tetFraction = r.real(0.004, 0.2);  // max tet volume / the surface's bounding box volume
  to.order = r.range(1, 2);
  to.preserveSurface = r.flag();
  to.timeLimitSeconds = 5;  // a TetGen run that refines without end is an InputError after 5 s
  static const bool fullTetgen = std::getenv("PECTUS_FUZZ_FULL_TETGEN") != nullptr;
  constexpr int kAddedPoints = 64;
  if (!fullTetgen) to.maxAddedPoints = kAddedPoints;
  try {
    const auto cage = nuss::cageFromMesh(m);
    Eigen::AlignedBox3d box;
    for (const auto& v : cage.surface.V) box.extend(v);
    to.maxVolume = tetFraction * box.sizes().prod();
    PECTUS_FUZZ_CHECK(cage.surface.F.size() == cage.surface.faceTissue.size());
    PECTUS_FUZZ_CHECK(cage.facePart.size() == cage.surface.F.size());
    PECTUS_FUZZ_CHECK(cage.nodeOfVertex.size() == m.vert.size());
    // the feature a TetGen failure's message names: a valid vertex, an edge or a face it is not a corner of,
    // no larger than the median edge
    const fe::SurfaceFeature sf = fe::smallestFeature(cage.surface);
    if (sf.vertex >= 0) {
      const int nsv = int(cage.surface.V.size());
      PECTUS_FUZZ_CHECK(sf.vertex < nsv && (sf.face < 0) == (sf.other >= 0));
      PECTUS_FUZZ_CHECK(sf.face < 0 || sf.face < int(cage.surface.F.size()));
      if (sf.face >= 0)
        for (int v : cage.surface.F[std::size_t(sf.face)]) PECTUS_FUZZ_CHECK(v != sf.vertex);
      PECTUS_FUZZ_CHECK(sf.other < nsv);
      PECTUS_FUZZ_CHECK(!(sf.size > sf.medianEdge) && !(sf.size < 0));
    }
    std::vector<int> tetFace;
    const auto tm = fe::tetrahedralize(cage.surface, to, &tetFace);
    const int nn = tm.numNodes();
    PECTUS_FUZZ_CHECK(nn >= int(cage.surface.V.size()));
    for (std::size_t i = 0; i < cage.surface.V.size(); ++i)
      PECTUS_FUZZ_CHECK((tm.nodes[i] - cage.surface.V[i]).norm() <= 1e-9 * (1 + cage.surface.V[i].norm()));
    PECTUS_FUZZ_CHECK(tm.tissue.size() == tm.tets.size() && tetFace.size() == tm.tets.size());
    std::vector<char> inTet(std::size_t(nn), 0);
    for (int t = 0; t < tm.numTets(); ++t) {
      for (int k = 0; k < tm.nodesPerTet(); ++k) {
        PECTUS_FUZZ_CHECK(tm.tets[t][k] >= 0 && tm.tets[t][k] < nn);
        inTet[std::size_t(tm.tets[t][k])] = 1;
      }
      PECTUS_FUZZ_CHECK(tetFace[t] >= 0 && tetFace[t] < int(cage.surface.F.size()));
      PECTUS_FUZZ_CHECK(tm.tetVolume(t) > 0);
    }
    for (std::size_t i = 0; i < cage.surface.V.size(); ++i) PECTUS_FUZZ_CHECK(inTet[i]);
    const auto bf = fe::boundaryFaces(tm);
    PECTUS_FUZZ_CHECK(tm.tets.empty() || !bf.empty());
  } catch (const InputError&) {
  }
  return 0;
}
