#include "pectus/c1_cmesh.h"

#include <vcg/complex/complex.h>

namespace pectus::c1 {

TriMesh toTriMesh(const CMeshO& m, std::vector<int>* vertexIndex) {
  TriMesh t;
  const std::vector<int> map = liveVertices(m, t.V, vertexIndex);
  t.F.reserve(m.face.size());
  for (const auto& f : m.face) {
    if (f.IsD()) continue;
    t.F.push_back({map[vcg::tri::Index(m, f.cV(0))], map[vcg::tri::Index(m, f.cV(1))], map[vcg::tri::Index(m, f.cV(2))]});
  }
  return t;
}

void fromTriMesh(const TriMesh& t, CMeshO& m, const std::vector<Vec3>* normals) {
  m.Clear();
  auto vi = vcg::tri::Allocator<CMeshO>::AddVertices(m, t.V.size());
  for (std::size_t i = 0; i < t.V.size(); ++i, ++vi) {
    vi->P() = toPoint(t.V[i]);
    if (normals) vi->N() = toPoint((*normals)[i]);
  }
  auto fi = vcg::tri::Allocator<CMeshO>::AddFaces(m, t.F.size());
  for (std::size_t i = 0; i < t.F.size(); ++i, ++fi)
    for (int k = 0; k < 3; ++k) fi->V(k) = &m.vert[t.F[i][k]];
}

}  // namespace pectus::c1
