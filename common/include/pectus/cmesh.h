// MeshLab's own vcglib mesh type (CMeshO), without Qt or the MeshLab document: the algorithm cores
// work on it directly so that the adapters pass `MeshModel::cm` through without copies.
#pragma once
#ifndef MESHLAB_SCALAR
#error "MESHLAB_SCALAR must be defined (float, the ABI of Debian's MeshLab); link pectus::vcg"
#endif
#if __has_include(<common/ml_mesh_type.h>)
#include <common/ml_mesh_type.h>  // MeshLab 2020.09
#else
#include <common/ml_document/cmesh.h>  // MeshLab 2021.05 and later
#endif

#include <Eigen/Dense>
#include <vector>

namespace pectus {
inline Eigen::Vector3d toEigen(const Point3m& p) { return {double(p[0]), double(p[1]), double(p[2])}; }
inline Point3m toPoint(const Eigen::Vector3d& p) { return Point3m(Scalarm(p[0]), Scalarm(p[1]), Scalarm(p[2])); }

/// Appends the positions of the live vertices of `m` to `V` in order and returns, per m.vert index, the
/// index in V (-1 for deleted vertices); `vertexIndex`, if given, receives for each vertex of V its index
/// in m.vert.
inline std::vector<int> liveVertices(const CMeshO& m, std::vector<Eigen::Vector3d>& V,
                                     std::vector<int>* vertexIndex = nullptr) {
  std::vector<int> map(m.vert.size(), -1);
  if (vertexIndex) vertexIndex->clear();
  for (std::size_t i = 0; i < m.vert.size(); ++i) {
    if (m.vert[i].IsD()) continue;
    map[i] = int(V.size());
    V.push_back(toEigen(m.vert[i].cP()));
    if (vertexIndex) vertexIndex->push_back(int(i));
  }
  return map;
}

/// A CMeshO owned by the program (a test, a fuzz target, a tool) rather than by MeshLab's document: vcglib
/// 2020.09's TriMesh destructor calls Clear() but not ClearAttributes(), so the named attributes of a plain
/// CMeshO (the tissue/part face labels) leak when it goes out of scope; this one frees them.
struct OwnedMesh : CMeshO {
  OwnedMesh() = default;
  OwnedMesh(const OwnedMesh&) = delete;
  OwnedMesh& operator=(const OwnedMesh&) = delete;
  ~OwnedMesh() { ClearAttributes(); }
};
}  // namespace pectus
