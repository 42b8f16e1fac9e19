#include "pectus/nuss/tissue_join.h"

#include <algorithm>
#include <cctype>
#include <map>
#include <memory>
#include <numeric>
#include <sstream>

#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <vcg/complex/allocate.h>

#include "pectus/errors.h"
#include "pectus/self_intersections.h"
#include "pectus/surface.h"

namespace pectus::nuss {

namespace {

namespace PMP = CGAL::Polygon_mesh_processing;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
using Primitive = CGAL::AABB_face_graph_triangle_primitive<Mesh>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;
using Inside = CGAL::Side_of_triangle_mesh<Mesh, K>;

// tie priority in an overlap, lower wins (cartilage over sternum over bone)
int priority(Tissue t) { return t == Tissue::Cartilage ? 0 : t == Tissue::Sternum ? 1 : 2; }

struct Solid {
  std::string name;
  Tissue tissue = Tissue::Unknown;
  Mesh mesh;
  std::vector<int> part;  // per face index
  std::unique_ptr<Tree> tree;
  std::unique_ptr<Inside> inside;
  void index() {
    tree = std::make_unique<Tree>(faces(mesh).first, faces(mesh).second, mesh);
    tree->accelerate_distance_queries();
    inside = std::make_unique<Inside>(*tree);
  }
  // (squared distance, part) of the face nearest to p
  std::pair<double, int> nearest(const Point& p) const {
    const auto [q, f] = tree->closest_point_and_primitive(p);
    return {CGAL::squared_distance(p, q), part[f.idx()]};
  }
};

std::string where(const Point& p) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(1);
  s << "(" << p.x() << ", " << p.y() << ", " << p.z() << ") mm";
  return s.str();
}

// no edge in more than two faces, no vertex in more than one fan
bool manifold(const Topology& t) {
  return t.nonManifoldEdges() == 0 && std::all_of(t.fans.begin(), t.fans.end(), [](int n) { return n <= 1; });
}

// the edge of face f between vertices a and b
const Topology::Edge& edgeOf(const Topology& t, std::size_t f, std::size_t a, std::size_t b) {
  for (int e : t.faceEdge[f]) {
    if (e < 0) continue;
    const Topology::Edge& E = t.edges[std::size_t(e)];  // E.a < E.b
    if (std::size_t(E.a) == std::min(a, b) && std::size_t(E.b) == std::max(a, b)) return E;
  }
  throw InternalError("tissue join: a face's corners are not the ends of its edges");
}

// The border edges of a manifold soup, and where the last one starts in the oriented polygons' face and
// corner order: the point the message names, where polygon_soup_to_polygon_mesh ends its last border
// halfedge (it creates the edges in that order, a border halfedge opposite its face's).
struct Border {
  int edges = 0;
  std::size_t lastStart = 0;
};
Border border(const Topology& t, const std::vector<std::vector<std::size_t>>& polys) {
  Border b;
  for (std::size_t f = 0; f < polys.size(); ++f)
    for (std::size_t j = 0; j < 3; ++j)
      if (edgeOf(t, f, polys[f][j], polys[f][(j + 1) % 3]).faces == 1) ++b.edges, b.lastStart = polys[f][j];
  return b;
}

// the layer as a closed, outward-oriented, self-intersection-free CGAL mesh; the face labels' parts
// (if any) kept in face order
Solid toSolid(const TissueLayer& l, Tissue tissue) {
  Solid s;
  s.name = l.name;
  s.tissue = tissue;
  const CMeshO& m = *l.mesh;
  const auto labels = readFaceLabels(m);
  std::vector<Point> pts;
  std::vector<std::vector<std::size_t>> polys;
  std::vector<int> vid(m.vert.size(), -1);
  for (std::size_t f = 0; f < m.face.size(); ++f) {
    const auto& F = m.face[f];
    if (F.IsD()) continue;
    std::vector<std::size_t> poly;
    for (int k = 0; k < 3; ++k) {
      const std::size_t v = vcg::tri::Index(m, F.cV(k));
      if (vid[v] < 0) {
        const auto& p = m.vert[v].cP();
        if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
          throw InputError("Layer '" + l.name + "': vertex " + std::to_string(v) + " has a non-finite coordinate.");
        vid[v] = static_cast<int>(pts.size());
        pts.emplace_back(p[0], p[1], p[2]);
      }
      poly.push_back(std::size_t(vid[v]));
    }
    if (poly[0] == poly[1] || poly[1] == poly[2] || poly[0] == poly[2]) continue;  // degenerate by index
    polys.push_back(poly);
    s.part.push_back(labels ? labels->part[f] : 0);
  }
  if (polys.empty()) throw TopologyError("Layer '" + l.name + "' has no faces: each tissue layer must be a closed surface.");
  Surface soup;
  for (const auto& p : pts) soup.V.emplace_back(p.x(), p.y(), p.z());
  for (const auto& q : polys) soup.F.push_back({int(q[0]), int(q[1]), int(q[2])});
  const Topology topo(soup);
  // CGAL's orientation fails on a non-manifold soup too, and on a non-orientable one
  if (!manifold(topo) || !PMP::orient_polygon_soup(pts, polys) || !PMP::is_polygon_soup_a_polygon_mesh(polys))
    throw TopologyError("Layer '" + l.name + "' is not a 2-manifold surface (an edge in more than two faces): repair it "
                     "(e.g. Filters > Cleaning and Repairing > Repair non Manifold Edges) before the analysis.");
  if (const Border b = border(topo, polys); b.edges > 0)
    throw TopologyError("Layer '" + l.name + "' is open (" + std::to_string(b.edges) + " border edges, e.g. at " +
                     where(pts[b.lastStart]) +
                     "): each tissue layer must be a closed surface; close its holes (Filters > Remeshing > Close Holes) "
                     "or export the segmentation as closed surfaces.");
  PMP::polygon_soup_to_polygon_mesh(pts, polys, s.mesh);
  for (std::size_t f = 0; f < polys.size(); ++f)  // the oriented faces
    soup.F[f] = {int(polys[f][0]), int(polys[f][1]), int(polys[f][2])};
  if (const auto pairs = selfIntersections(soup.V, soup.F); !pairs.empty())
    throw TopologyError("Layer '" + l.name + "' intersects itself (" + std::to_string(pairs.size()) + " face pairs, e.g. near " +
                     where(pts[polys[std::size_t(pairs.front().a)][0]]) +
                     "): repair it (Filters > Cleaning and Repairing > Select Self Intersecting Faces shows where).");
  PMP::orient_to_bound_a_volume(s.mesh);
  return s;
}

// a bone layer labelled as the vertebral column throughout (the support 'Pectus: Prepare Patient Rib Cage' can keep)
bool column(const Solid& s) {
  return !s.part.empty() && std::all_of(s.part.begin(), s.part.end(), [](int p) { return p == kVertebralColumn; });
}

// parts of unlabelled layers: bone pieces from the nearest joint, sternum body, cartilage from the nearest
// rib (not the vertebral column)
void assignParts(std::vector<Solid>& solids, const std::vector<Landmark>& lms) {
  for (auto& s : solids) {
    if (std::any_of(s.part.begin(), s.part.end(), [](int p) { return p != 0; })) continue;
    if (s.tissue == Tissue::Sternum) std::fill(s.part.begin(), s.part.end(), kSternumBody);
    if (s.tissue != Tissue::Bone) continue;
    auto comp = s.mesh.add_property_map<Mesh::Face_index, std::size_t>("f:comp").first;
    const std::size_t n = PMP::connected_components(s.mesh, comp);
    std::vector<double> best(n, 1e300);
    std::vector<int> code(n, 0);
    for (auto f : faces(s.mesh))
      for (auto v : vertices_around_face(halfedge(f, s.mesh), s.mesh))
        for (const auto& l : lms) {
          const int side = l.code / 100, rib = l.code % 100;
          if (!(side == 1 || side == 2) || rib < 1 || rib > 12) continue;
          const auto& p = s.mesh.point(v);
          const double d = (Eigen::Vector3d(p.x(), p.y(), p.z()) - l.p).squaredNorm();
          if (d < best[comp[f]]) best[comp[f]] = d, code[comp[f]] = l.code;
        }
    for (auto f : faces(s.mesh)) s.part[f.idx()] = code[comp[f]];
    s.mesh.remove_property_map(comp);
  }
  for (auto& s : solids) s.index();
  for (auto& s : solids) {
    if (s.tissue != Tissue::Cartilage || std::any_of(s.part.begin(), s.part.end(), [](int p) { return p != 0; })) continue;
    for (auto f : faces(s.mesh)) {
      const Point c = CGAL::centroid(s.mesh.point(target(halfedge(f, s.mesh), s.mesh)),
                                     s.mesh.point(target(next(halfedge(f, s.mesh), s.mesh), s.mesh)),
                                     s.mesh.point(source(halfedge(f, s.mesh), s.mesh)));
      double bd = 1e300;
      for (const auto& b : solids)
        if (b.tissue == Tissue::Bone && !column(b))
          if (const auto [d, p] = b.nearest(c); d < bd) bd = d, s.part[f.idx()] = p;
    }
  }
}

}  // namespace

Tissue tissueFromName(const std::string& name) {
  std::string n = name;
  std::transform(n.begin(), n.end(), n.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  auto has = [&](const char* w) { return n.find(w) != std::string::npos; };
  if (has("cartilag")) return Tissue::Cartilage;
  if (has("stern") || has("manubr") || has("xiph")) return Tissue::Sternum;
  if (has("rib") || has("bone") || has("costa")) return Tissue::Bone;
  return Tissue::Unknown;
}

namespace {

// the tissue of a layer: given, from its name, or the one tissue its faces are labelled with throughout
Tissue layerTissue(const TissueLayer& l) {
  Tissue t = l.tissue != Tissue::Unknown ? l.tissue : tissueFromName(l.name);
  if (t == Tissue::Unknown)
    if (const auto lab = readFaceLabels(*l.mesh)) {  // a layer labelled with one tissue throughout
      int first = 0;
      bool one = true;
      for (std::size_t f = 0; f < l.mesh->face.size(); ++f)
        if (!l.mesh->face[f].IsD()) {
          if (!first) first = lab->tissue[f];
          one = one && lab->tissue[f] == first;
        }
      if (one) t = Tissue(first);
    }
  if (t == Tissue::Unknown)
    throw InputError("Cannot tell the tissue of layer '" + l.name + "': rename it to contain 'rib' or 'bone', 'cartilage', "
                     "or 'sternum', or hide it if it is not part of the cage.");
  return t;
}

// one solid per layer, at least one of bone and one of cartilage
std::shared_ptr<std::vector<Solid>> solidsOf(const std::vector<TissueLayer>& layers) {
  auto solids = std::make_shared<std::vector<Solid>>();
  bool bone = false, cartilage = false;
  for (const auto& l : layers) {
    const Tissue t = layerTissue(l);
    bone = bone || t == Tissue::Bone;
    cartilage = cartilage || t == Tissue::Cartilage;
    solids->push_back(toSolid(l, t));
  }
  if (!bone || !cartilage)
    throw InputError(std::string("The tissue layers have no ") + (!bone ? "bone (rib)" : "cartilage") +
                     " layer: give one closed surface per tissue, named after it ('ribs', 'costal cartilage', 'sternum').");
  return solids;
}

// the union, cartilage first (the order does not change the union, only the corefinement's work)
Mesh unionOf(const std::vector<Solid>& solids, JoinStats* stats) {
  std::vector<int> order(solids.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return priority(solids[a].tissue) < priority(solids[b].tissue); });
  Mesh u = solids[order[0]].mesh;
  double sum = PMP::volume(u);
  for (std::size_t k = 1; k < order.size(); ++k) {
    Mesh b = solids[order[k]].mesh;  // corefinement changes both operands
    sum += PMP::volume(b);
    if (!PMP::corefine_and_compute_union(u, b, u))
      throw TopologyError("Joining layer '" + solids[order[k]].name +
                       "' to the others gives a non-manifold surface (the layers touch along an edge or at a vertex only): "
                       "let the touching tissues overlap a little, or merge those layers.");
  }
  if (stats) {
    auto comp = u.add_property_map<Mesh::Face_index, std::size_t>("f:c").first;
    *stats = {static_cast<int>(solids.size()), sum, PMP::volume(u), static_cast<int>(PMP::connected_components(u, comp))};
    u.remove_property_map(comp);
  }
  return u;
}

// the label of the input surface nearest to q (ties by priority): (tissue, part)
std::pair<int, int> nearestLabel(const std::vector<Solid>& solids, const Point& q) {
  double bd = 1e300;
  int bt = 0, bp = 0, bprio = 9;
  for (const auto& s : solids) {
    const auto [d, p] = s.nearest(q);
    const bool tie = std::abs(d - bd) <= 1e-10;
    if ((d < bd && !tie) || (tie && priority(s.tissue) < bprio)) bd = std::min(bd, d), bt = int(s.tissue), bp = p, bprio = priority(s.tissue);
  }
  return {bt, bp};
}

// the union into the CMeshO, each face labelled by the input surface it lies on (nearest; ties by priority)
void toLabelledMesh(const Mesh& u, const std::vector<Solid>& solids, CMeshO& joined) {
  joined.Clear();
  std::map<Mesh::Vertex_index, std::size_t> vi;
  auto v = vcg::tri::Allocator<CMeshO>::AddVertices(joined, u.number_of_vertices());
  for (auto x : vertices(u)) {
    const auto& p = u.point(x);
    v->P() = Point3m(Scalarm(p.x()), Scalarm(p.y()), Scalarm(p.z()));
    vi[x] = std::size_t(v - joined.vert.begin());
    ++v;
  }
  std::vector<int> tissue, part;
  for (auto f : faces(u)) {
    std::array<std::size_t, 3> c{};
    int k = 0;
    for (auto x : vertices_around_face(halfedge(f, u), u)) c[std::size_t(k++)] = vi[x];
    vcg::tri::Allocator<CMeshO>::AddFace(joined, &joined.vert[c[0]], &joined.vert[c[1]], &joined.vert[c[2]]);
    const auto h = halfedge(f, u);
    const Point q = CGAL::centroid(u.point(source(h, u)), u.point(target(h, u)), u.point(target(next(h, u), u)));
    const auto [bt, bp] = nearestLabel(solids, q);
    tissue.push_back(bt);
    part.push_back(bp);
  }
  writeFaceLabels(joined, tissue, part);
  vcg::tri::UpdateBounding<CMeshO>::Box(joined);
}

// each tet takes the tissue and part of the solid its centroid lies deepest in (ties: priority); a tet in
// no solid (a rounding sliver at the union's surface) keeps the nearest face's label
void labelTetsBySolids(const std::vector<Solid>& solids, fe::TetMesh& mesh, std::vector<int>& tetPart) {
  std::vector<const Solid*> byPriority;
  for (const auto& s : solids) byPriority.push_back(&s);
  std::stable_sort(byPriority.begin(), byPriority.end(), [](const Solid* a, const Solid* b) { return priority(a->tissue) < priority(b->tissue); });
  for (int t = 0; t < mesh.numTets(); ++t) {
    const Eigen::Vector3d c = mesh.centroid(t);
    const Point p(c.x(), c.y(), c.z());
    const Solid* in = nullptr;
    double depth = -1;
    for (const Solid* s : byPriority)
      if ((*s->inside)(p) != CGAL::ON_UNBOUNDED_SIDE)
        if (const double d = s->tree->squared_distance(p); d > depth) in = s, depth = d;  // ties: priority
    if (in) {  // in no solid (a rounding sliver at the union's surface): the nearest face's label stays
      mesh.tissue[std::size_t(t)] = int(in->tissue);
      tetPart[std::size_t(t)] = in->nearest(p).second;
    }
  }
}

}  // namespace

CageSurface joinTissueLayers(const std::vector<TissueLayer>& layers, const std::vector<Landmark>& lms, CMeshO& joined,
                             JoinStats* stats) {
  const std::shared_ptr<std::vector<Solid>> solids = solidsOf(layers);
  assignParts(*solids, lms);
  const Mesh u = unionOf(*solids, stats);
  toLabelledMesh(u, *solids, joined);
  CageSurface cage = cageFromMesh(joined);
  cage.labelTets = [solids](fe::TetMesh& mesh, std::vector<int>& tetPart) { labelTetsBySolids(*solids, mesh, tetPart); };
  return cage;
}

}  // namespace pectus::nuss
