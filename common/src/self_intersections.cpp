#include "pectus/self_intersections.h"

#include <algorithm>
#include <vector>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

namespace pectus {

std::vector<FacePair> selfIntersections(const std::vector<Eigen::Vector3d>& points,
                                        const std::vector<std::array<int, 3>>& triangles) {
  namespace PMP = CGAL::Polygon_mesh_processing;
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Mesh = CGAL::Surface_mesh<K::Point_3>;
  std::vector<FacePair> out;
  std::vector<K::Point_3> pts;
  pts.reserve(points.size());
  for (const auto& p : points) pts.emplace_back(p.x(), p.y(), p.z());
  // soup: triangles repeating a vertex or pointing outside the points are degenerate and left out
  std::vector<std::vector<std::size_t>> polys;
  std::vector<int> faceOf;
  polys.reserve(triangles.size());
  const int n = static_cast<int>(points.size());
  for (std::size_t f = 0; f < triangles.size(); ++f) {
    const auto& t = triangles[f];
    const bool valid = t[0] >= 0 && t[1] >= 0 && t[2] >= 0 && t[0] < n && t[1] < n && t[2] < n;
    if (!valid || t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
      out.push_back({int(f), int(f)});
      continue;
    }
    polys.push_back({std::size_t(t[0]), std::size_t(t[1]), std::size_t(t[2])});
    faceOf.push_back(int(f));
  }
  // orientation only changes the order of a triangle's corners; touching sheets get their own copy of
  // the vertex (the faces then meet at a point they do not share: reported as intersecting)
  if (!PMP::is_polygon_soup_a_polygon_mesh(polys)) PMP::orient_polygon_soup(pts, polys);
  Mesh mesh;
  PMP::polygon_soup_to_polygon_mesh(pts, polys, mesh);  // face i of mesh is polys[i]
  std::vector<std::pair<Mesh::Face_index, Mesh::Face_index>> pairs;
  PMP::self_intersections(mesh, std::back_inserter(pairs));
  for (const auto& [x, y] : pairs) {
    const int a = faceOf[x.idx()], b = faceOf[y.idx()];
    out.push_back({std::min(a, b), std::max(a, b)});
  }
  // degenerate faces first (a crossing next to one is often just its collapsed corner touching a neighbour)
  std::sort(out.begin(), out.end(), [](const FacePair& x, const FacePair& y) {
    const bool dx = x.a == x.b, dy = y.a == y.b;
    return dx != dy ? dx : (x.a != y.a ? x.a < y.a : x.b < y.b);
  });
  return out;
}

std::vector<int> facesOf(const std::vector<FacePair>& pairs) {
  std::vector<int> f;
  f.reserve(2 * pairs.size());
  for (const auto& p : pairs) f.push_back(p.a), f.push_back(p.b);
  std::sort(f.begin(), f.end());
  f.erase(std::unique(f.begin(), f.end()), f.end());
  return f;
}

}  // namespace pectus
