#include "pectus/self_intersections.h"

#include <algorithm>
#include <exception>
#include <vector>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/Polygon_mesh_processing/manifoldness.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

namespace pectus {

namespace PMP = CGAL::Polygon_mesh_processing;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using SM = CGAL::Surface_mesh<K::Point_3>;

struct SelfIntersections::Mesh {
  SM mesh;
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
  meshFace_.assign(triangles.size(), -1);
  for (std::size_t i = 0; i < faceOf_.size(); ++i) meshFace_[std::size_t(faceOf_[i])] = int(i);
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

void SelfIntersections::moveTo(const std::vector<Eigen::Vector3d>& points) {
  std::size_t i = 0;
  for (const auto v : mesh_->mesh.vertices()) {
    const Eigen::Vector3d& p = points[mesh_->pointOf[i++]];
    mesh_->mesh.point(v) = K::Point_3(p.x(), p.y(), p.z());
  }
}

namespace {

using FoundPairs = std::vector<std::pair<SM::Face_index, SM::Face_index>>;

CGAL::Bbox_3 faceBox(const SM& mesh, SM::Face_index f) {
  CGAL::Bbox_3 bb;
  for (const auto v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) bb += mesh.point(v).bbox();
  return bb;
}

// CGAL's check on the faces in `range`: the crossing pairs of two faces in it
FoundPairs crossingsAmong(const std::vector<SM::Face_index>& range, const SM& mesh) {
  FoundPairs found;
  PMP::self_intersections(range, mesh, std::back_inserter(found));
  return found;
}

// Every crossing pair of the mesh, on two threads. The faces are split at the median centre of their boxes
// along the longest axis of the mesh's box, into A (boxes that start below the median) and B (boxes that
// end at or above it). Two crossing faces have overlapping boxes, so both are in A or both in B: a face
// not in A starts at or above the median, so the other's box ends there or above. Each half is CGAL's
// check; the few faces in both halves may give a pair twice, which the caller keeps once.
FoundPairs allCrossings(const SM& mesh) {
  constexpr std::size_t kSplitFrom = 4000;  // a small mesh: one check, without the boxes and the thread start
  if (mesh.number_of_faces() < kSplitFrom) {
    FoundPairs found;
    PMP::self_intersections(mesh, std::back_inserter(found));
    return found;
  }
  std::vector<CGAL::Bbox_3> box;
  box.reserve(mesh.number_of_faces());
  CGAL::Bbox_3 all;
  for (const auto f : mesh.faces()) all += box.emplace_back(faceBox(mesh, f));
  int axis = 0;
  for (int d = 1; d < 3; ++d)
    if (all.max(d) - all.min(d) > all.max(axis) - all.min(axis)) axis = d;
  std::vector<double> centre;
  centre.reserve(box.size());
  for (const auto& b : box) centre.push_back(0.5 * (b.min(axis) + b.max(axis)));
  std::nth_element(centre.begin(), centre.begin() + std::ptrdiff_t(centre.size() / 2), centre.end());
  const double median = centre[centre.size() / 2];
  std::vector<SM::Face_index> half[2];
  std::size_t i = 0;
  for (const auto f : mesh.faces()) {
    const CGAL::Bbox_3& b = box[i++];
    if (b.min(axis) < median) half[0].push_back(f);
    if (b.max(axis) >= median) half[1].push_back(f);
  }
  FoundPairs found[2];
  std::exception_ptr failed[2];
#pragma omp parallel for num_threads(2) schedule(static, 1)
  for (int h = 0; h < 2; ++h) try {
      found[h] = crossingsAmong(half[h], mesh);
    } catch (...) {
      failed[h] = std::current_exception();
    }
  for (const auto& e : failed)
    if (e) std::rethrow_exception(e);
  found[0].insert(found[0].end(), found[1].begin(), found[1].end());
  return std::move(found[0]);
}

}  // namespace

std::vector<FacePair> SelfIntersections::pairs(const std::vector<std::size_t>* faces, std::vector<FacePair> out) const {
  FoundPairs found;
  if (faces == nullptr) {
    found = allCrossings(mesh_->mesh);
  } else {
    std::vector<SM::Face_index> range;
    range.reserve(faces->size());
    for (std::size_t f : *faces) range.push_back(SM::Face_index(SM::size_type(f)));
    found = crossingsAmong(range, mesh_->mesh);
  }
  for (const auto& [x, y] : found) {
    const int a = faceOf_[x.idx()], b = faceOf_[y.idx()];
    out.push_back({std::min(a, b), std::max(a, b)});
  }
  // degenerate faces first (a crossing next to one is often just its collapsed corner touching a
  // neighbour); a pair found twice is kept once
  const auto before = [](const FacePair& x, const FacePair& y) {
    const bool dx = x.a == x.b, dy = y.a == y.b;
    return dx != dy ? dx : (x.a != y.a ? x.a < y.a : x.b < y.b);
  };
  std::sort(out.begin(), out.end(), before);
  out.erase(std::unique(out.begin(), out.end(), [](const FacePair& x, const FacePair& y) { return x.a == y.a && x.b == y.b; }),
            out.end());
  return out;
}

std::vector<FacePair> SelfIntersections::operator()(const std::vector<Eigen::Vector3d>& points) {
  moveTo(points);
  return pairs(nullptr, degenerate_);
}

std::vector<FacePair> SelfIntersections::involving(const std::vector<int>& triangles,
                                                   const std::vector<Eigen::Vector3d>& points) {
  moveTo(points);
  const auto& mesh = mesh_->mesh;
  std::vector<char> given(faceOf_.size(), 0);
  std::vector<FacePair> out;
  for (int t : triangles) {
    if (t < 0 || std::size_t(t) >= meshFace_.size()) continue;
    if (meshFace_[std::size_t(t)] < 0) out.push_back({t, t});
    else given[std::size_t(meshFace_[std::size_t(t)])] = 1;
  }
  // the faces whose boxes meet a given face's box (CGAL's box intersection, the given faces against all)
  using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::size_t>;
  std::vector<Box> all, mine;
  all.reserve(faceOf_.size());
  for (const auto f : mesh.faces()) {
    all.emplace_back(faceBox(mesh, f), std::size_t(f.idx()));
    if (given[f.idx()]) mine.push_back(all.back());
  }
  std::vector<char> inRange = given;
  CGAL::box_intersection_d(mine.begin(), mine.end(), all.begin(), all.end(),
                           [&](const Box&, const Box& b) { inRange[b.info()] = 1; });
  std::vector<std::size_t> range;
  for (std::size_t f = 0; f < inRange.size(); ++f)
    if (inRange[f]) range.push_back(f);
  std::vector<FacePair> found = pairs(&range, out);
  // pairs of two faces in the range but neither given were not asked for (a degenerate pair was)
  found.erase(std::remove_if(found.begin(), found.end(),
                             [&](const FacePair& p) {
                               const int fa = meshFace_[std::size_t(p.a)], fb = meshFace_[std::size_t(p.b)];
                               return fa >= 0 && fb >= 0 && !given[std::size_t(fa)] && !given[std::size_t(fb)];
                             }),
              found.end());
  return found;
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
