#include "self_intersections.h"

#include "pectus/self_intersections.h"

namespace pectus::ribcage {

std::vector<int> selfIntersectingFaces(const CMeshO& m) {
  std::vector<Eigen::Vector3d> pts;
  const std::vector<int> vi = liveVertices(m, pts);
  std::vector<std::array<int, 3>> tris;
  std::vector<int> faceOf;
  for (std::size_t f = 0; f < m.face.size(); ++f) {
    const auto& F = m.face[f];
    if (F.IsD()) continue;
    tris.push_back({vi[vcg::tri::Index(m, F.cV(0))], vi[vcg::tri::Index(m, F.cV(1))], vi[vcg::tri::Index(m, F.cV(2))]});
    faceOf.push_back(int(f));
  }
  std::vector<int> out = facesOf(selfIntersections(pts, tris));
  for (int& f : out) f = faceOf[std::size_t(f)];
  return out;
}

}  // namespace pectus::ribcage
