#include "pectus/self_intersections.h"

#include <algorithm>
#include <vector>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/manifoldness.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

namespace pectus {

namespace PMP = CGAL::Polygon_mesh_processing;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;

struct SelfIntersections::Mesh {
  CGAL::Surface_mesh<K::Point_3> mesh;
  std::vector<std::size_t> pointOf;  // mesh vertex -> point (a vertex split by the orientation is a copy)
};

SelfIntersections::SelfIntersections(std::size_t numPoints, const std::vector<std::array<int, 3>>& triangles)
    : mesh_(std::make_unique<Mesh>()) {
  // soup: triangles repeating a vertex or pointing outside the points are degenerate and left out
  std::vector<std::vector<std::size_t>> polys;
  polys.reserve(triangles.size());
  const auto n = static_cast<long long>(numPoints);
  for (std::size_t f = 0; f < triangles.size(); ++f) {
    const auto& t = triangles[f];
    const bool valid = t[0] >= 0 && t[1] >= 0 && t[2] >= 0 && t[0] < n && t[1] < n && t[2] < n;
    if (!valid || t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
      degenerate_.push_back({int(f), int(f)});
      continue;
    }
    polys.push_back({std::size_t(t[0]), std::size_t(t[1]), std::size_t(t[2])});
    faceOf_.push_back(int(f));
  }
  if (buildAsGiven(numPoints, polys)) return;
  // orientation only changes the order of a triangle's corners; touching sheets get their own copy of
  // the vertex (the faces then meet at a point they do not share: reported as intersecting). The soup's
  // "points" are the point indices, so a copy carries the index of the point it copies.
  std::vector<std::size_t> soupPoint(numPoints);
  for (std::size_t i = 0; i < numPoints; ++i) soupPoint[i] = i;
  PMP::orient_polygon_soup(soupPoint, polys);
  // the mesh (face i is polys[i]) is built on placeholder points whose x is the soup point's index, which
  // then gives each mesh vertex its point; each call sets the positions
  std::vector<K::Point_3> placeholder(soupPoint.size());
  for (std::size_t i = 0; i < soupPoint.size(); ++i) placeholder[i] = K::Point_3(double(i), 0, 0);
  PMP::polygon_soup_to_polygon_mesh(placeholder, polys, mesh_->mesh);
  for (const auto v : mesh_->mesh.vertices())
    mesh_->pointOf.push_back(soupPoint[std::size_t(mesh_->mesh.point(v).x())]);
}

// The common case, a consistently oriented 2-manifold (every smoother input, every closed tissue surface):
// the mesh is built face by face as given, in a fifth of the time the soup's orientation takes on 75k
// triangles. Surface_mesh::add_face refuses a face across an edge used twice in one direction or at a
// vertex closed on every side; a vertex that still joins two sheets is found after. Either leaves the
// mesh empty and returns false, for the soup's orientation to mend.
bool SelfIntersections::buildAsGiven(std::size_t numPoints, const std::vector<std::vector<std::size_t>>& polys) {
  auto& mesh = mesh_->mesh;
  using SM = CGAL::Surface_mesh<K::Point_3>;
  auto vertex = [](std::size_t i) { return SM::Vertex_index(SM::size_type(i)); };
  mesh.reserve(SM::size_type(numPoints), SM::size_type(2 * polys.size()), SM::size_type(polys.size()));
  for (std::size_t i = 0; i < numPoints; ++i) mesh.add_vertex();
  bool ok = true;
  for (const auto& p : polys)
    if (mesh.add_face(vertex(p[0]), vertex(p[1]), vertex(p[2])) == SM::null_face()) {
      ok = false;
      break;
    }
  std::vector<SM::Halfedge_index> pinched;
  if (ok) PMP::non_manifold_vertices(mesh, std::back_inserter(pinched));
  if (!ok || !pinched.empty()) {
    mesh.clear();
    return false;
  }
  mesh_->pointOf.resize(numPoints);
  for (std::size_t i = 0; i < numPoints; ++i) mesh_->pointOf[i] = i;
  return true;
}

SelfIntersections::~SelfIntersections() = default;

std::vector<FacePair> SelfIntersections::operator()(const std::vector<Eigen::Vector3d>& points) {
  auto& mesh = mesh_->mesh;
  std::size_t i = 0;
  for (const auto v : mesh.vertices()) {
    const Eigen::Vector3d& p = points[mesh_->pointOf[i++]];
    mesh.point(v) = K::Point_3(p.x(), p.y(), p.z());
  }
  std::vector<FacePair> out = degenerate_;
  std::vector<std::pair<CGAL::SM_Face_index, CGAL::SM_Face_index>> pairs;
  PMP::self_intersections(mesh, std::back_inserter(pairs));
  for (const auto& [x, y] : pairs) {
    const int a = faceOf_[x.idx()], b = faceOf_[y.idx()];
    out.push_back({std::min(a, b), std::max(a, b)});
  }
  // degenerate faces first (a crossing next to one is often just its collapsed corner touching a neighbour)
  std::sort(out.begin(), out.end(), [](const FacePair& x, const FacePair& y) {
    const bool dx = x.a == x.b, dy = y.a == y.b;
    return dx != dy ? dx : (x.a != y.a ? x.a < y.a : x.b < y.b);
  });
  return out;
}

std::vector<FacePair> selfIntersections(const std::vector<Eigen::Vector3d>& points,
                                        const std::vector<std::array<int, 3>>& triangles) {
  return SelfIntersections(points.size(), triangles)(points);
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
