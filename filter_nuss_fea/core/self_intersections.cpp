#include "self_intersections.h"

#include <algorithm>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

namespace pectus::ribcage {

std::vector<int> selfIntersectingFaces(const CMeshO& m) {
  namespace PMP = CGAL::Polygon_mesh_processing;
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Mesh = CGAL::Surface_mesh<K::Point_3>;
  std::vector<K::Point_3> pts;
  pts.reserve(m.vert.size());
  for (const auto& v : m.vert) pts.emplace_back(v.cP()[0], v.cP()[1], v.cP()[2]);
  std::vector<std::array<std::size_t, 3>> tris;
  std::vector<int> faceOf;
  for (std::size_t f = 0; f < m.face.size(); ++f) {
    const auto& F = m.face[f];
    if (F.IsD()) continue;
    tris.push_back({std::size_t(vcg::tri::Index(m, F.cV(0))), std::size_t(vcg::tri::Index(m, F.cV(1))),
                    std::size_t(vcg::tri::Index(m, F.cV(2)))});
    faceOf.push_back(int(f));
  }
  Mesh mesh;
  PMP::polygon_soup_to_polygon_mesh(pts, tris, mesh);  // face i of mesh is tris[i]
  std::vector<std::pair<Mesh::Face_index, Mesh::Face_index>> pairs;
  PMP::self_intersections(mesh, std::back_inserter(pairs));
  std::vector<int> out;
  for (const auto& [a, b] : pairs) out.push_back(faceOf[a.idx()]), out.push_back(faceOf[b.idx()]);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace pectus::ribcage
