#include "pectus/patient/soup.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <set>
#include <tuple>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/triangulate_faces.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Bounded_normal_change_filter.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Constrained_placement.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Edge_length_cost.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Edge_length_stop_predicate.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Midpoint_placement.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>
#include <CGAL/boost/graph/generators.h>
#include <CGAL/boost/graph/helpers.h>
#include <vcg/complex/allocate.h>

#include "pectus/self_intersections.h"

namespace pectus::patient {

namespace {
using Vec3 = Eigen::Vector3d;

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Mesh = CGAL::Surface_mesh<K::Point_3>;

// the soup as CGAL's polygon soup functions take it: points and index triples
std::pair<std::vector<K::Point_3>, std::vector<std::vector<std::size_t>>> polygonSoupOf(const Soup& s) {
  std::pair<std::vector<K::Point_3>, std::vector<std::vector<std::size_t>>> out;
  for (const auto& p : s.V) out.first.emplace_back(p.x(), p.y(), p.z());
  for (const auto& f : s.F) out.second.push_back({std::size_t(f[0]), std::size_t(f[1]), std::size_t(f[2])});
  return out;
}

// the faces of a CGAL surface mesh (polygons fanned into triangles)
template <class Mesh>
Soup soupOfSurfaceMesh(const Mesh& m) {
  Soup out;
  std::vector<int> id(m.number_of_vertices() + m.number_of_removed_vertices(), -1);
  for (auto v : m.vertices()) {
    id[v.idx()] = int(out.V.size());
    const auto& p = m.point(v);
    out.V.emplace_back(p.x(), p.y(), p.z());
  }
  for (auto f : m.faces()) {
    std::vector<int> t;
    for (auto v : m.vertices_around_face(m.halfedge(f))) t.push_back(id[v.idx()]);
    for (std::size_t k = 1; k + 1 < t.size(); ++k) out.F.push_back({t[0], t[k], t[k + 1]});
  }
  return out;
}
}  // namespace

void weld(Soup& s) {
  std::map<std::tuple<double, double, double>, int> at;
  std::vector<int> to(s.V.size());
  std::vector<Vec3> V;
  for (std::size_t i = 0; i < s.V.size(); ++i) {
    const auto key = std::make_tuple(s.V[i].x(), s.V[i].y(), s.V[i].z());
    const auto [it, fresh] = at.emplace(key, int(V.size()));
    if (fresh) V.push_back(s.V[i]);
    to[i] = it->second;
  }
  std::vector<std::array<int, 3>> F;
  for (auto f : s.F) {
    for (int& v : f) v = to[std::size_t(v)];
    if (f[0] != f[1] && f[1] != f[2] && f[0] != f[2]) F.push_back(f);
  }
  // drop unused vertices
  std::vector<int> used(V.size(), -1);
  Soup out;
  for (auto f : F) {
    for (int& v : f) {
      if (used[std::size_t(v)] < 0) used[std::size_t(v)] = int(out.V.size()), out.V.push_back(V[std::size_t(v)]);
      v = used[std::size_t(v)];
    }
    out.F.push_back(f);
  }
  s = std::move(out);
}

void append(Soup& to, const Soup& s) {
  const int o = int(to.V.size());
  to.V.insert(to.V.end(), s.V.begin(), s.V.end());
  for (auto f : s.F) to.F.push_back({f[0] + o, f[1] + o, f[2] + o});
}

std::vector<Soup> components(const Soup& s) {
  std::vector<int> faceComponent;
  std::vector<Soup> out(std::size_t(Topology(s).components(faceComponent)));
  std::vector<std::map<int, int>> vmap(out.size());
  for (std::size_t fi = 0; fi < s.F.size(); ++fi) {
    const auto& f = s.F[fi];
    Soup& c = out[std::size_t(faceComponent[fi])];
    auto& vm = vmap[std::size_t(faceComponent[fi])];
    std::array<int, 3> g{};
    for (int k = 0; k < 3; ++k) {
      const auto [jt, nv] = vm.emplace(f[std::size_t(k)], int(c.V.size()));
      if (nv) c.V.push_back(s.V[std::size_t(f[std::size_t(k)])]);
      g[std::size_t(k)] = jt->second;
    }
    c.F.push_back(g);
  }
  return out;
}

double area(const Soup& s) {
  double a = 0;
  for (const auto& f : s.F)
    a += 0.5 * (s.V[std::size_t(f[1])] - s.V[std::size_t(f[0])]).cross(s.V[std::size_t(f[2])] - s.V[std::size_t(f[0])]).norm();
  return a;
}

Vec3 centroid(const Soup& s) {
  Vec3 c = Vec3::Zero();
  double w = 0;
  for (const auto& f : s.F) {
    const Vec3 &a = s.V[std::size_t(f[0])], &b = s.V[std::size_t(f[1])], &d = s.V[std::size_t(f[2])];
    const double ar = 0.5 * (b - a).cross(d - a).norm();
    c += ar * (a + b + d) / 3.0, w += ar;
  }
  return w > 0 ? Vec3(c / w) : (s.V.empty() ? Vec3::Zero() : s.V.front());
}

double volume(const Soup& s) {
  const Vec3 o = centroid(s);
  double v = 0;
  for (const auto& f : s.F)
    v += (s.V[std::size_t(f[0])] - o).dot((s.V[std::size_t(f[1])] - o).cross(s.V[std::size_t(f[2])] - o)) / 6.0;
  return std::abs(v);
}

void transform(Soup& s, const Eigen::Matrix3d& R, const Vec3& t) {
  for (auto& p : s.V) p = R * p + t;
  if (R.determinant() < 0)
    for (auto& f : s.F) std::swap(f[1], f[2]);
}

int removeDuplicateFaces(Soup& s) {
  std::set<std::array<int, 3>> seen;
  std::vector<std::array<int, 3>> F;
  for (const auto& f : s.F) {
    auto k = f;
    std::sort(k.begin(), k.end());
    if (seen.insert(k).second) F.push_back(f);
  }
  const int removed = int(s.F.size() - F.size());
  s.F = std::move(F);
  return removed;
}

// A collapse that makes the surface cross itself is undone by collapsing again from the input with the edges
// near the crossing kept: every edge with a vertex within kKeepMargin edge lengths of a crossing face's box
// (grown by that much again on each attempt), so that the rest of the surface still loses its short edges.
constexpr int kCollapseAttempts = 4;
constexpr double kKeepMargin = 2.0;

int collapseShortEdges(Soup& s, double minLength, int* keptEdges) {
  namespace PMP = CGAL::Polygon_mesh_processing;
  namespace SMS = CGAL::Surface_mesh_simplification;
  if (keptEdges) *keptEdges = 0;
  auto [pts, polys] = polygonSoupOf(s);
  if (!PMP::is_polygon_soup_a_polygon_mesh(polys)) return 0;
  Mesh input;
  PMP::polygon_soup_to_polygon_mesh(pts, polys, input);
  if (!CGAL::is_closed(input)) return 0;
  const SMS::Edge_length_stop_predicate<double> stop(minLength);
  std::vector<Eigen::AlignedBox3d> keep;  // where collapsing made the surface cross itself
  const auto inKept = [&](const K::Point_3& p) {
    const Vec3 q(p.x(), p.y(), p.z());
    return std::any_of(keep.begin(), keep.end(), [&](const Eigen::AlignedBox3d& b) { return b.contains(q); });
  };
  for (int attempt = 0; attempt < kCollapseAttempts; ++attempt) {
    Mesh m = input;
    auto constrained = m.add_property_map<Mesh::Edge_index, bool>("e:kept", false).first;
    int kept = 0;
    for (auto e : m.edges())
      if (inKept(m.point(m.vertex(e, 0))) || inKept(m.point(m.vertex(e, 1)))) put(constrained, e, true), ++kept;
    // a vertex on a kept edge stays where it is
    const SMS::Constrained_placement<SMS::Midpoint_placement<Mesh>, decltype(constrained)> placement(constrained);
    SMS::edge_collapse(m, stop, CGAL::parameters::edge_is_constrained_map(constrained)
                                    .get_cost(SMS::Edge_length_cost<Mesh>())
                                    .get_placement(placement)
                                    .filter(SMS::Bounded_normal_change_filter<>()));
    m.collect_garbage();
    const int collapsed = int(input.number_of_faces() - m.number_of_faces()) / 2;  // each collapse removes two faces
    if (collapsed == 0) return 0;
    Soup out = soupOfSurfaceMesh(m);
    const auto crossing = selfIntersections(out.V, out.F);
    if (crossing.empty()) {
      s = std::move(out);
      if (keptEdges) *keptEdges = kept;
      return collapsed;
    }
    const double margin = kKeepMargin * minLength * (attempt + 1);
    for (const auto& [a, b] : crossing)
      for (const std::size_t f : {std::size_t(a), std::size_t(b)}) {
        Eigen::AlignedBox3d box;
        for (int k = 0; k < 3; ++k) box.extend(out.V[std::size_t(out.F[f][std::size_t(k)])]);
        keep.emplace_back(box.min() - Vec3::Constant(margin), box.max() + Vec3::Constant(margin));
      }
  }
  return -1;
}

std::string defects(const Soup& s) {
  if (s.F.empty()) return "no faces";
  const Topology t(s);
  if (t.badFace >= 0)
    return "invalid (face " + std::to_string(t.badFace) + " uses vertex index " + std::to_string(t.badIndex) + ")";
  std::set<std::array<int, 3>> seen;
  std::size_t dup = 0;
  for (const auto& f : s.F) {
    auto k = f;
    std::sort(k.begin(), k.end());
    if (!seen.insert(k).second) ++dup;
  }
  if (dup) return std::to_string(dup) + " duplicate faces";
  // edges as a table of every face's local edges counts them: a degenerate face's collapsed edge too
  const Topology::EdgeUse use = t.edgeUse();
  if (use.moreThanTwice) return std::to_string(use.moreThanTwice) + " non-manifold edges";
  if (use.once) return "open (" + std::to_string(use.once) + " border edges)";
  // a vertex whose faces form more than one fan (two sheets touching at a point)
  if (const auto pinched = std::count_if(t.fans.begin(), t.fans.end(), [](int n) { return n > 1; }))
    return std::to_string(pinched) + " non-manifold vertices";
  if (const auto pairs = selfIntersections(s.V, s.F); !pairs.empty())
    return "intersects itself (" + std::to_string(pairs.size()) + " face pairs)";
  return "";
}

}  // namespace pectus::patient
