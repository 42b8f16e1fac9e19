#include "pectus/surface_cmesh.h"

#include <vcg/complex/complex.h>

#include "pectus/self_intersections.h"

namespace pectus {

Surface surfaceOf(const CMeshO& m, const SurfaceOf& how, std::vector<int>* vertexOf, std::vector<int>* faceOf) {
  Surface s;
  if (vertexOf) vertexOf->clear();
  if (faceOf) faceOf->clear();
  std::vector<int> id(m.vert.size(), -1);
  auto addVertex = [&](std::size_t i) {
    id[i] = int(s.V.size());
    s.V.push_back(toEigen(m.vert[i].cP()));
    if (vertexOf) vertexOf->push_back(int(i));
  };
  if (how.vertices != SurfaceOf::Vertices::UsedByFaces)
    for (std::size_t i = 0; i < m.vert.size(); ++i)
      if (how.vertices == SurfaceOf::Vertices::All || !m.vert[i].IsD()) addVertex(i);
  s.F.reserve(m.face.size());
  for (std::size_t fi = 0; fi < m.face.size(); ++fi) {
    const auto& f = m.face[fi];
    if (f.IsD() || (how.keepFace && !how.keepFace(fi))) continue;
    std::array<int, 3> t{};
    bool finite = true;
    for (int k = 0; k < 3; ++k) {
      t[std::size_t(k)] = int(vcg::tri::Index(m, f.cV(k)));
      if (how.skipNonFiniteFaces && !toEigen(m.vert[std::size_t(t[std::size_t(k)])].cP()).allFinite()) finite = false;
    }
    if (!finite) continue;
    for (int& v : t) {
      if (id[std::size_t(v)] < 0 && how.vertices == SurfaceOf::Vertices::UsedByFaces) addVertex(std::size_t(v));
      v = id[std::size_t(v)];
    }
    s.F.push_back(t);
    if (faceOf) faceOf->push_back(int(fi));
  }
  return s;
}

void toMesh(const Surface& s, CMeshO& m, const std::vector<Eigen::Vector3d>* normals) {
  m.Clear();
  auto vi = vcg::tri::Allocator<CMeshO>::AddVertices(m, s.V.size());
  for (std::size_t i = 0; i < s.V.size(); ++i, ++vi) {
    vi->P() = toPoint(s.V[i]);
    if (normals) vi->N() = toPoint((*normals)[i]);
  }
  auto fi = vcg::tri::Allocator<CMeshO>::AddFaces(m, s.F.size());
  for (std::size_t i = 0; i < s.F.size(); ++i, ++fi)
    for (int k = 0; k < 3; ++k) fi->V(k) = &m.vert[std::size_t(s.F[i][std::size_t(k)])];
}

std::vector<int> selfIntersectingFaces(const CMeshO& m) {
  std::vector<int> faceOf;
  const Surface s = surfaceOf(m, {}, nullptr, &faceOf);
  std::vector<int> out = facesOf(selfIntersections(s.V, s.F));
  for (int& f : out) f = faceOf[std::size_t(f)];
  return out;
}

}  // namespace pectus
