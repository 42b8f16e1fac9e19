#include "pectus/nuss/nuss_analysis.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <sstream>

#include "pectus/errors.h"
#include "pectus/format.h"
#include "pectus/union_find.h"
#include "pectus/mesh_checks.h"

namespace pectus::nuss {

using Eigen::Vector3d;
using Clock = std::chrono::steady_clock;

namespace {

double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

std::string mm(double v, int prec = 1) { return fixedText(v, prec); }

std::string pointText(const Vector3d& p) { return "(" + mm(p.x()) + ", " + mm(p.y()) + ", " + mm(p.z()) + ") mm"; }

}  // namespace

std::string partName(int tissue, int part) {
  if (part == kManubrium) return "manubrium";
  if (part == kSternumBody) return "sternum body";
  if (part == kXiphoid) return "xiphoid";
  if (part == kVertebralColumn) return "vertebral column";
  const int side = part / 100, rib = part % 100;
  if ((side == 1 || side == 2) && rib >= 1 && rib <= 12)
    return std::string(side == 1 ? "right " : "left ") +
           (tissue == int(Tissue::Cartilage) ? "costal cartilage " : "rib ") + std::to_string(rib);
  return std::string(tissueName(Tissue(tissue))) + " (part " + std::to_string(part) + ")";
}

std::string Location::where() const {
  std::string s = partName(tissue, part) + " (" + tissueName(Tissue(tissue)) + ")";
  if (distanceToJoint >= 0)
    s += distanceToJoint <= kNearSpine ? ", posterior near the spine, " + mm(distanceToJoint, 0) + " mm from its costovertebral joint"
                                       : ", " + mm(distanceToJoint, 0) + " mm from its costovertebral joint";
  return s;
}

std::string Location::describe() const { return where() + " at " + pointText(p); }

CageSurface cageFromMesh(const CMeshO& m) {
  if (m.fn == 0) throw TopologyError("The layer has no faces: the Nuss FE analysis needs the closed, labelled rib cage surface.");
  const auto labels = readFaceLabels(m);
  if (!labels)
    throw InputError(
        "The layer has no tissue labels: every face needs a tissue (bone, cartilage or sternum) and an anatomical part, "
        "as 'Pectus: Create Rib Cage' writes them (attribute pectus_tissue/pectus_part, or the tissue face colours "
        "with face quality = tissue*1000 + part; save PLY with face colour and quality): " + faceLabelProblem(m) + ".");
  for (size_t i = 0; i < m.vert.size(); ++i) {
    if (m.vert[i].IsD()) continue;
    const auto& p = m.vert[i].cP();
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
      throw InputError("Vertex " + std::to_string(i) + " has a non-finite coordinate.");
  }
  if (const std::size_t dup = inspectMesh(m).duplicateFaces)
    throw TopologyError(std::to_string(dup) + " duplicate faces (the same three vertices as another face): remove them "
                     "(Cleaning: Remove Duplicate Faces); a closed surface has each face once.");
  // weld micro-edges (shorter than 1e-3 x the mean edge length: marching-cubes / STL slivers that
  // TetGen cannot mesh) by collapsing them; faces that become degenerate or doubled are dropped
  UnionFind sets(m.vert.size());
  double sum = 0;
  std::size_t ne = 0;
  for (const auto& F : m.face)
    if (!F.IsD())
      for (int k = 0; k < 3; ++k) sum += vcg::Distance(F.cP(k), F.cP((k + 1) % 3)), ++ne;
  const double tol = 1e-3 * sum / std::max<std::size_t>(ne, 1);
  for (const auto& F : m.face)
    if (!F.IsD())
      for (int k = 0; k < 3; ++k)
        if (vcg::Distance(F.cP(k), F.cP((k + 1) % 3)) < tol)
          sets.unite(int(vcg::tri::Index(m, F.cV(k))), int(vcg::tri::Index(m, F.cV((k + 1) % 3))));
  // vertices no live face references (left by deleting faces, or by a segmentation tool) are dropped:
  // TetGen would keep them as nodes without elements, and the stiffness would be singular there
  std::vector<char> used(m.vert.size(), 0);
  for (const auto& F : m.face)
    if (!F.IsD())
      for (int k = 0; k < 3; ++k) used[vcg::tri::Index(m, F.cV(k))] = 1;
  CageSurface c;
  std::vector<int> compact(m.vert.size(), -1);
  for (size_t i = 0; i < m.vert.size(); ++i) {
    if (m.vert[i].IsD()) continue;
    if (!used[i]) { ++c.unreferencedVertices; continue; }
    const int r = sets.find(int(i));
    if (compact[r] < 0) {
      compact[r] = static_cast<int>(c.surface.V.size());
      const auto& p = m.vert[r].cP();
      c.surface.V.emplace_back(p[0], p[1], p[2]);
    }
  }
  c.nodeOfVertex.assign(m.vert.size(), -1);
  for (size_t i = 0; i < m.vert.size(); ++i)
    if (!m.vert[i].IsD() && used[i]) c.nodeOfVertex[i] = compact[sets.find(int(i))];
  std::map<std::array<int, 3>, int> seen;  // sorted vertex triple -> count
  std::vector<std::array<int, 3>> faces;
  std::vector<int> tissue, part;
  for (size_t f = 0; f < m.face.size(); ++f) {
    const auto& F = m.face[f];
    if (F.IsD()) continue;
    std::array<int, 3> t{};
    for (int k = 0; k < 3; ++k) t[k] = c.nodeOfVertex[vcg::tri::Index(m, F.cV(k))];
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) { ++c.weldedFaces; continue; }
    auto key = t;
    std::sort(key.begin(), key.end());
    seen[key]++;
    faces.push_back(t);
    tissue.push_back(labels->tissue[f]);
    part.push_back(labels->part[f]);
  }
  for (size_t f = 0; f < faces.size(); ++f) {
    auto key = faces[f];
    std::sort(key.begin(), key.end());
    if (c.weldedFaces > 0 && seen[key] == 2) { ++c.weldedFaces; continue; }  // a collapsed tent leaves a doubled face
    c.surface.F.push_back(faces[f]);
    c.surface.faceTissue.push_back(tissue[f]);
    c.facePart.push_back(part[f]);
  }
  return c;
}

Vector3d Analysis::displacementAt(const Vector3d& p) const {
  int best = 0;
  double bd = 1e300;
  for (int i = 0; i < mesh.numNodes(); ++i) {
    const double d = (mesh.nodes[i] - p).squaredNorm();
    if (d < bd) bd = d, best = i;
  }
  return result.u.size() ? Vector3d(result.displacement(best)) : Vector3d::Zero();
}

namespace {

// surface vertices (= mesh nodes 0..nv-1) of faces with a given predicate, within r of c
std::vector<int> surfaceNodesNear(const CageSurface& cage, const Vector3d& c, double r,
                                  const std::function<bool(size_t)>& facePred) {
  std::vector<char> take(cage.surface.V.size(), 0);
  for (size_t f = 0; f < cage.surface.F.size(); ++f) {
    if (!facePred(f)) continue;
    for (int v : cage.surface.F[f])
      if ((cage.surface.V[v] - c).norm() <= r) take[v] = 1;
  }
  std::vector<int> out;
  for (size_t v = 0; v < take.size(); ++v)
    if (take[v]) out.push_back(static_cast<int>(v));
  return out;
}

// the surface vertex of a part's faces nearest to p (-1 if the part has no face)
int nearestVertexOfPart(const CageSurface& cage, int part, const Vector3d& p, int tissue = 0) {
  int best = -1;
  double bd = 1e300;
  for (size_t f = 0; f < cage.surface.F.size(); ++f) {
    if (cage.facePart[f] != part || (tissue && cage.surface.faceTissue[f] != tissue)) continue;
    for (int v : cage.surface.F[f]) {
      const double d = (cage.surface.V[v] - p).squaredNorm();
      if (d < bd) bd = d, best = v;
    }
  }
  return best;
}

}  // namespace

Vector3d barExit(const CageSurface& cage, const std::vector<Landmark>& lms, int side, int space) {
  if (auto p = findLandmark(lms, barExitLandmark(side, space))) return *p;
  const char* sideName = side == 1 ? "right" : "left";
  if (space < 1)
    throw InputError("Intercostal space " + std::to_string(space) + " does not exist: spaces are numbered from 1 (between ribs 1 and 2).");
  Vector3d mid = Vector3d::Zero();
  for (int rib : {space, space + 1}) {
    const int part = ribPart(side, rib);
    std::vector<char> on(cage.surface.V.size(), 0);
    double xmax = -1;
    for (size_t f = 0; f < cage.surface.F.size(); ++f)
      if (cage.facePart[f] == part && cage.surface.faceTissue[f] == int(Tissue::Bone))
        for (int v : cage.surface.F[f]) on[v] = 1, xmax = std::max(xmax, std::abs(cage.surface.V[v].x()));
    if (xmax < 0)
      throw InputError("No bar exit landmark for intercostal space " + std::to_string(space) + " on the " + sideName + " (code " +
                       std::to_string(barExitLandmark(side, space)) + ") and the cage has no " + partName(int(Tissue::Bone), part) +
                       " to place it: the intercostal space lies outside the ribs; choose a space between two ribs or give the exit points.");
    Vector3d c = Vector3d::Zero();
    int n = 0;
    for (size_t v = 0; v < on.size(); ++v)
      if (on[v] && std::abs(cage.surface.V[v].x()) >= xmax - 10.0) c += cage.surface.V[v], ++n;
    mid += 0.5 * c / n;
  }
  return mid;
}

namespace {

// the user's sternum point, else landmark 500; `why` ends the message when there is neither
Vector3d lowerSternumEnd(const std::vector<Landmark>& lms, const Placement& pl, const std::string& why) {
  if (pl.sternumPoint) return *pl.sternumPoint;
  if (auto p = findLandmark(lms, kSternumLowerEnd)) return *p;
  throw InputError("No lower sternum end landmark (code 500) and no sternum point given: " + why + ".");
}

constexpr int kMinJointNodes = 4;  // fixed nodes per costovertebral joint, at least
// fixed nodes closer than this fraction of the mean edge length to one line hold a piece only on that line
constexpr double kMinOffLine = 0.1;

// mm: how far the points stray from one line: the largest distance of a point from the line through the
// first point and the point farthest from it (0 for fewer than two distinct points). A piece held only at
// points on one line turns freely about it (a mid-edge node of a TET10 lies on its edge, so the nodes
// nearest to a point are often two corners and the mid-edge nodes between and beyond them)
double offLine(const std::vector<Vector3d>& pts) {
  if (pts.size() < 3) return 0;
  const Vector3d& a = pts.front();
  const Vector3d b = *std::max_element(pts.begin(), pts.end(), [&](const Vector3d& p, const Vector3d& q) {
    return (p - a).squaredNorm() < (q - a).squaredNorm();
  });
  const double len = (b - a).norm();
  if (!(len > 0)) return 0;
  const Vector3d dir = (b - a) / len;
  double off = 0;
  for (const Vector3d& p : pts) off = std::max(off, (p - a - (p - a).dot(dir) * dir).norm());
  return off;
}

// mm: the mean length of the faces' edges (an edge of two faces counted twice)
double meanEdgeLength(const fe::SurfaceMesh& s) {
  double sum = 0;
  for (const auto& f : s.F)
    for (int k = 0; k < 3; ++k) sum += (s.V[size_t(f[k])] - s.V[size_t(f[(k + 1) % 3])]).norm();
  return sum / double(std::max<std::size_t>(3 * s.F.size(), 1));
}

// the fixed nodes, the Fe nodes and the four Fsr patches, into s (s.mesh: the tet mesh of cage)
void checkRadii(const Placement& pl) {
  if (!kPatchRadiusRange.contains(pl.jointRadius) || !kPatchRadiusRange.contains(pl.sternumLoadRadius) ||
      !kPatchRadiusRange.contains(pl.ribSupportRadius))
    throw InputError("The joint, sternum load and rib support radii must lie in " + kPatchRadiusRange.text() + " mm.");
  if (!(pl.sternoclavicularRadius == 0 || kPatchRadiusRange.contains(pl.sternoclavicularRadius)))
    throw InputError("The sternoclavicular support radius must be 0 (no support) or lie in " + kPatchRadiusRange.text() + " mm.");
  if (pl.direction.norm() < 1e-12 || !pl.direction.allFinite()) throw InputError("The force direction must be a non-zero vector.");
}

void placeLoads(const CageSurface& cage, const std::vector<Landmark>& lms, const Placement& pl, Analysis& s);

// fixes a joint's nodes of its own rib, `own` as (distance, node): those within the radius, at least the
// kMinJointNodes nearest, and the next nearest while those fixed lie on one line (closer than kMinOffLine x
// spacing to it); returns the distance of the farthest fixed (0 if none)
double fixOwnNodes(const fe::TetMesh& mesh, std::vector<std::pair<double, int>>& own, double radius, double spacing,
                   std::vector<char>& fixed) {
  std::sort(own.begin(), own.end());
  std::vector<Vector3d> held;
  size_t n = 0;
  for (; n < own.size(); ++n) {
    if (n >= size_t(kMinJointNodes) && own[n].first > radius && offLine(held) >= kMinOffLine * spacing) break;
    fixed[size_t(own[n].second)] = 1;
    held.push_back(mesh.nodes[size_t(own[n].second)]);
  }
  return n > 0 ? own[n - 1].first : 0.0;
}

void place(const CageSurface& cage, const std::vector<Landmark>& lms, const Placement& pl, Analysis& s) {
  const fe::TetMesh& mesh = s.mesh;
  checkRadii(pl);
  // fixed: all mesh nodes (surface and interior) near a costovertebral joint landmark, and every node of the
  // vertebral column's tets when the column is in the model
  std::vector<char> fixed(mesh.nodes.size(), 0);
  const double spacing = meanEdgeLength(cage.surface);
  // the parts of the tets at each node, to find a joint's nodes on its own rib
  std::vector<std::vector<int>> partsAt(mesh.nodes.size());
  for (int t = 0; t < mesh.numTets(); ++t)
    for (int k = 0; k < mesh.nodesPerTet(); ++k) {
      auto& p = partsAt[size_t(mesh.tets[size_t(t)][size_t(k)])];
      if (std::find(p.begin(), p.end(), s.tetPart[size_t(t)]) == p.end()) p.push_back(s.tetPart[size_t(t)]);
    }
  int joints = 0;
  for (const auto& l : lms) {
    const int side = l.code / 100, rib = l.code % 100;
    if (!(side == 1 || side == 2) || rib < 1 || rib > 12) continue;
    ++joints;
    // each joint fixes the nodes within the joint radius and at least the four nodes of its own rib nearest
    // to it (of any part if the model has no tets of that rib): a coarse or smoothed mesh may have fewer
    // within the radius, and a rib held only at its joint (the floating ribs, separate pieces of the
    // surface) needs three non-collinear nodes of its own fixed, not those of the rib next to it; while the
    // rib's nodes fixed so far lie on one line, the next nearest is fixed too; a landmark more than two mean
    // edge lengths beyond the radius from every node is not on this cage
    const int part = ribPart(side, rib);
    const bool ribInModel = std::find(s.tetPart.begin(), s.tetPart.end(), part) != s.tetPart.end();
    double nearest = std::numeric_limits<double>::infinity();
    std::vector<std::pair<double, int>> own;  // (distance, node) of the joint's rib
    for (int i = 0; i < mesh.numNodes(); ++i) {
      const double d = (mesh.nodes[i] - l.p).norm();
      nearest = std::min(nearest, d);
      const auto& p = partsAt[size_t(i)];
      if (d <= pl.jointRadius) fixed[i] = 1;
      if (!ribInModel || std::find(p.begin(), p.end(), part) != p.end()) own.emplace_back(d, i);
    }
    if (nearest > pl.jointRadius + 2 * spacing)
      throw InputError("The costovertebral joint of the " + partName(1, l.code) + " at " + pointText(l.p) + " lies " + mm(nearest) +
                       " mm from the nearest mesh node, more than the joint radius (" + mm(pl.jointRadius) + " mm) and two mean edge lengths (" +
                       mm(2 * spacing) + " mm): the landmark layer does not belong to this cage; pick the cage's landmark layer or increase the joint radius.");
    const double farthest = fixOwnNodes(mesh, own, pl.jointRadius, spacing, fixed);
    if (farthest > pl.jointRadius) {
      ++s.jointsWidened;
      s.widestJointRadius = std::max(s.widestJointRadius, farthest);
    }
  }
  if (joints == 0)
    throw InputError(
        "No costovertebral joint landmarks (codes 100*side + rib) in the landmark layer: the analysis fixes the ribs there. "
        "Pick the landmark layer written by 'Pectus: Create Rib Cage' or add one vertex per joint with that code as quality.");
  s.fixedAtJoints = int(std::count(fixed.begin(), fixed.end(), char(1)));
  // the vertebral column kept as the support ('Pectus: Prepare Patient Rib Cage', part kVertebralColumn): all of it
  for (int t = 0; t < mesh.numTets(); ++t)
    if (s.tetPart[size_t(t)] == kVertebralColumn)
      for (int k = 0; k < mesh.nodesPerTet(); ++k) fixed[size_t(mesh.tets[size_t(t)][size_t(k)])] |= 2;
  for (int i = 0; i < mesh.numNodes(); ++i) {
    if (fixed[i]) s.fixedNodes.push_back(i);
    if (fixed[i] == 2) ++s.fixedOnColumn;
  }
  if (pl.sternoclavicularRadius > 0) {
    const Landmark* notch = nullptr;
    for (const auto& l : lms)
      if (l.code == kSternumUpperEnd) notch = &l;
    if (!notch)
      throw InputError("The sternoclavicular support needs the jugular notch (landmark 502) in the landmark layer: add it, or set the "
                       "sternoclavicular radius to 0.");
    s.sternoclavicularNodes = surfaceNodesNear(cage, notch->p, pl.sternoclavicularRadius,
                                               [&](size_t f) { return cage.surface.faceTissue[f] == int(Tissue::Sternum); });
    if (s.sternoclavicularNodes.empty())
      throw InputError("No sternum surface node lies within " + mm(pl.sternoclavicularRadius) + " mm of the jugular notch " + pointText(notch->p) +
                       ": increase the sternoclavicular radius.");
  }
  placeLoads(cage, lms, pl, s);
}

// the Fe patch(es) on the sternum and the Fsr patches on the ribs (surface nodes only)
void placeLoads(const CageSurface& cage, const std::vector<Landmark>& lms, const Placement& pl, Analysis& s) {
  auto sternumFace = [&](size_t f) { return cage.surface.faceTissue[f] == int(Tissue::Sternum); };
  const Vector3d sp = lowerSternumEnd(lms, pl, "the elevating force goes there");
  bool anySternum = false;
  for (size_t f = 0; f < cage.surface.F.size() && !anySternum; ++f) anySternum = sternumFace(f);
  if (!anySternum) throw InputError("The cage has no sternum faces (tissue code 3): the elevating force acts on the sternum.");
  s.sternumNodes = surfaceNodesNear(cage, sp, pl.sternumLoadRadius, sternumFace);
  if (s.sternumNodes.empty())
    throw InputError("No sternum surface node lies within " + mm(pl.sternumLoadRadius) + " mm of the lower sternum end " + pointText(sp) +
                     ": increase the sternum load radius or move the point onto the sternum.");

  // the rib supports of a bar in `space`: ribs space and space+1 next to its exits, both sides
  auto barSupports = [&](int space, const std::string& bar) {
    std::array<Vector3d, 2> exits;
    for (int side = 1; side <= 2; ++side) {
      std::optional<Vector3d> exit = bar.empty() ? (side == 1 ? pl.exitRight : pl.exitLeft) : std::nullopt;
      if (!exit) exit = barExit(cage, lms, side, space);
      exits[side - 1] = *exit;
      for (int rib : {space, space + 1}) {
        const int part = ribPart(side, rib);
        const int v = nearestVertexOfPart(cage, part, *exit, int(Tissue::Bone));
        const std::string name = partName(int(Tissue::Bone), part);
        if (v < 0) throw InputError("The cage has no bone faces of the " + name + ": the rib support force of the" + bar + " bar exit goes there.");
        const Vector3d c = cage.surface.V[v];
        auto nodes = surfaceNodesNear(cage, c, pl.ribSupportRadius, [&](size_t f) { return cage.facePart[f] == part; });
        if ((c - *exit).norm() > 40)
          throw InputError("The " + name + " is " + mm((c - *exit).norm(), 0) + " mm from the" + bar + " bar exit " + pointText(*exit) +
                           ": the exit point is not between ribs " + std::to_string(space) + " and " + std::to_string(space + 1) + ".");
        s.supportNodes.push_back(nodes);
        s.supportNames.push_back(name);
      }
    }
    return exits;
  };
  const auto exits1 = barSupports(pl.intercostalSpace, "");
  if (pl.secondSpace == 0) return;

  // the second bar: parallel to the first, its sternal patch at the lower sternum end moved up or down
  // by the height difference of the two bars' exits: around the sternum surface node of that height nearest
  // to the centre of the sternum's section there (a node, so that a coarse sternum, whose section centre
  // may lie farther than the load radius from every node, still gets a patch)
  if (pl.secondSpace == pl.intercostalSpace)
    throw InputError("The second bar must go into another intercostal space than the first (both in " + std::to_string(pl.secondSpace) + ").");
  if (!kSecondShareRange.contains(pl.secondShare))
    throw InputError("The second bar's share of the force must lie in " + kSecondShareRange.text() + ".");
  const auto exits2 = barSupports(pl.secondSpace, " second");
  const double z2 = sp.z() + 0.5 * (exits2[0].z() + exits2[1].z() - exits1[0].z() - exits1[1].z());
  std::vector<int> band;
  Vector3d centre = Vector3d::Zero();
  for (size_t f = 0; f < cage.surface.F.size(); ++f)
    if (sternumFace(f))
      for (int v : cage.surface.F[f])
        if (std::abs(cage.surface.V[v].z() - z2) <= pl.sternumLoadRadius) centre += cage.surface.V[v], band.push_back(v);
  if (band.empty())
    throw InputError("The second bar (intercostal space " + std::to_string(pl.secondSpace) + ") crosses the midline at z = " + mm(z2) +
                     " mm, where the cage has no sternum: choose a space whose bar meets the sternum.");
  centre /= double(band.size());
  const int c2 = *std::min_element(band.begin(), band.end(), [&](int a, int b) {
    return (cage.surface.V[a] - centre).squaredNorm() < (cage.surface.V[b] - centre).squaredNorm();
  });
  s.secondSternumNodes = surfaceNodesNear(cage, cage.surface.V[c2], pl.sternumLoadRadius, sternumFace);
  s.secondShare = pl.secondShare;
}

// what to tell when the stiffness matrix cannot be factorised although every piece is held: TetGen without
// quality refinement leaves nearly flat tets (slivers) between nearly coplanar surface points (the cage's
// midline, coarse edges); their stiffness makes the matrix numerically indefinite
std::string slivers(const Analysis& a) {
  double mean = 0;
  for (int t = 0; t < a.mesh.numTets(); ++t) mean += std::abs(a.mesh.tetVolume(t)) / a.mesh.numTets();
  int n = 0, flattest = -1;
  for (int t = 0; t < a.mesh.numTets(); ++t)
    if (std::abs(a.mesh.tetVolume(t)) < 1e-6 * mean) {
      ++n;
      if (flattest < 0 || std::abs(a.mesh.tetVolume(t)) < std::abs(a.mesh.tetVolume(flattest))) flattest = t;
    }
  if (!n) return "";
  return " Here the tet mesh has " + std::to_string(n) + " nearly flat tets (slivers below 1e-6 of the mean tet volume; the "
         "flattest in the " + partName(a.mesh.tissue[flattest], a.tetPart[flattest]) + " at " + pointText(a.mesh.centroid(flattest)) +
         "): set a tet quality (radius-edge ratio, e.g. 1.6) or use a smaller edge length.";
}

// connected components of the tet mesh; every one must hold fixed nodes off one line (at least
// kMinOffLine x spacing, the surface's mean edge length, from it)
int checkComponents(const fe::TetMesh& mesh, const std::vector<int>& tetPart, const std::vector<int>& fixedNodes,
                    double spacing) {
  UnionFind sets(std::size_t(mesh.numNodes()));
  for (const auto& t : mesh.tets)
    for (int k = 1; k < mesh.nodesPerTet(); ++k) sets.unite(t[k], t[0]);
  std::map<int, std::vector<Vector3d>> fixedIn;
  for (int n : fixedNodes) fixedIn[sets.find(n)].push_back(mesh.nodes[size_t(n)]);
  std::map<int, int> compTet;
  for (int t = 0; t < mesh.numTets(); ++t) compTet.emplace(sets.find(mesh.tets[t][0]), t);
  for (const auto& [root, t] : compTet) {
    if (!fixedIn.count(root))
      throw TopologyError("A part of the model is not held by any costovertebral joint or the vertebral column (the connected piece containing the " +
                       partName(mesh.tissue[t], tetPart[t]) +
                       "): the system would be singular. Connect it to the cage, remove it, or add its joint landmark.");
    // held at nodes on one line only (one or two nodes, or the nodes of one edge): it turns about that line
    const auto& held = fixedIn.at(root);
    if (offLine(held) < kMinOffLine * spacing)
      throw TopologyError("A part of the model (the connected piece containing the " + partName(mesh.tissue[t], tetPart[t]) +
                          ") is held only at " + std::to_string(held.size()) + " fixed node(s) on one line, near " +
                          pointText(held.front()) + ": it turns freely about that line and the system would be singular. "
                          "Add its costovertebral joint landmark, or increase the joint radius so that the joint holding "
                          "it fixes more of it.");
  }
  // pieces that hang on the rest by a node or an edge only (tets sharing no face with it) turn about that
  // hinge freely: every piece of face-connected tets needs a fixed node of its own
  UnionFind tp(mesh.tets.size());
  std::map<std::array<int, 3>, int> faceTet;
  static const int kFaces[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  for (int t = 0; t < mesh.numTets(); ++t)
    for (const auto& f : kFaces) {
      std::array<int, 3> key{mesh.tets[t][f[0]], mesh.tets[t][f[1]], mesh.tets[t][f[2]]};
      std::sort(key.begin(), key.end());
      const auto [it, fresh] = faceTet.emplace(key, t);
      if (!fresh) tp.unite(t, it->second);
    }
  std::vector<char> fixed(mesh.numNodes(), 0);
  for (int n : fixedNodes) fixed[n] = 1;
  std::map<int, bool> held;
  for (int t = 0; t < mesh.numTets(); ++t) {
    bool& h = held[tp.find(t)];
    for (int k = 0; k < mesh.nodesPerTet(); ++k) h = h || fixed[mesh.tets[t][k]];
  }
  for (const auto& [root, h] : held)
    if (!h) {
      int n = 0;
      for (int t = 0; t < mesh.numTets(); ++t) n += tp.find(t) == root;
      throw TopologyError("A piece of the model (" + std::to_string(n) + " tets of the " + partName(mesh.tissue[root], tetPart[root]) +
                       " near " + pointText(mesh.centroid(root)) +
                       ") hangs on the rest by a single node or edge, no tet face: it turns freely about it and the system "
                       "would be singular. The surface is too coarse there (a thin part a few elements across, or two parts "
                       "touching at a point): use a smaller edge length or a maximum tet volume.");
    }
  // a node of no tet (a surface vertex TetGen left out) has no stiffness at all
  std::vector<char> used(mesh.numNodes(), 0);
  for (const auto& t : mesh.tets)
    for (int k = 0; k < mesh.nodesPerTet(); ++k) used[t[k]] = 1;
  for (int n = 0; n < mesh.numNodes(); ++n)
    if (!used[n])
      throw TopologyError("Node " + std::to_string(n) + " at " + pointText(mesh.nodes[n]) +
                       " belongs to no tetrahedron (TetGen left this surface vertex out): the system would be singular. "
                       "Remove near-duplicate vertices there (Cleaning: Merge Close Vertices) or use another edge length.");
  return static_cast<int>(compTet.size());
}

// each bar: Fe_i on its sternal patch, Fe_i / 4 opposite on each of its four rib patches
void addLoads(fe::Problem& p, const Analysis& a, const Vector3d& dir, double fe) {
  p.force.assign(p.mesh->nodes.size(), Vector3d::Zero());
  const bool two = !a.secondSternumNodes.empty();
  const double f1 = two ? fe * (1.0 - a.secondShare) : fe;
  auto bar = [&](const std::vector<int>& sternum, size_t firstSupport, double f) {
    for (int n : sternum) p.force[n] += dir * (f / sternum.size());
    for (size_t k = firstSupport; k < firstSupport + 4; ++k)
      for (int n : a.supportNodes[k]) p.force[n] -= dir * (f / 4.0 / a.supportNodes[k].size());
  };
  bar(a.sternumNodes, 0, f1);
  if (two) bar(a.secondSternumNodes, 4, fe * a.secondShare);
}

double elevationOf(const Eigen::VectorXd& u, const Analysis& a, const Vector3d& dir) {
  double e = 0;
  for (int n : a.sternumNodes) e += dir.dot(Vector3d(u.segment<3>(3 * n)));
  return e / a.sternumNodes.size();
}

}  // namespace

std::vector<std::string> newtonHistoryLines(const Analysis& a) {
  std::vector<std::string> lines;
  for (std::size_t k = 0; k < a.newtonHistory.size(); ++k) {
    const auto& h = a.newtonHistory[k];
    const bool first = k == 0 || a.newtonHistory[k - 1].increment != h.increment;
    lines.push_back(fe::newtonIterationText(h, first ? nullptr : &a.newtonHistory[k - 1]));
  }
  return lines;
}

std::string notReportableBecause(const fe::TetgenOptions& mesh, const CageSurface& cage) {
  std::vector<std::string> why;
  if (mesh.order != 2) why.push_back("linear TET4 locks in bending (stiffer than the converged TET10 mesh)");
  if (mesh.radiusEdgeRatio <= 0) why.push_back("tets without quality refinement (tet quality 0: about 12 % stiffer)");
  const double edge = meanEdgeLength(cage.surface);
  if (edge > kConvergedMeanEdgeMm)
    why.push_back("surface edges of " + fixedText(edge, 1) + " mm on average, coarser than the " +
                  fixedText(kConvergedMeanEdgeMm, 0) + " mm of the converged meshes");
  std::string text;
  for (const auto& w : why) text += (text.empty() ? "" : "; ") + w;
  return text;
}

const char* calibrationMethodName(CalibrationMethod m) {
  return m == CalibrationMethod::DisplacementControl ? "displacement" : "force";
}

CalibrationMethod parseCalibrationMethod(const std::string& name) {
  for (CalibrationMethod m : {CalibrationMethod::ForceSearch, CalibrationMethod::DisplacementControl})
    if (name == calibrationMethodName(m)) return m;
  throw InputError("Unknown calibration method '" + name +
                   "': use force (a search over the elevating force) or displacement (one solve driving the sternal "
                   "patch to the target elevation).");
}

fe::Problem problemAt(const Analysis& a, const Options& opt, double force) {
  fe::Problem p;
  p.mesh = &a.mesh;
  p.materials = fe::thesisMaterials(opt.nuBone, opt.nuCartilage, opt.material, opt.eBone, opt.eCartilage);
  for (int n : a.fixedNodes) p.fixNode(n);
  int axis = 0;
  opt.place.direction.cwiseAbs().maxCoeff(&axis);
  for (int n : a.sternoclavicularNodes) p.fixed.push_back({n, axis, 0.0});
  addLoads(p, a, opt.place.direction.normalized(), force);
  return p;
}

void checkPlacement(const CageSurface& cage, const std::vector<Landmark>& lms, const Placement& pl) {
  checkRadii(pl);
  Analysis scratch;
  placeLoads(cage, lms, pl, scratch);
}

Model buildModel(const CageSurface& cage, const fe::TetgenOptions& mesh) {
  const auto t0 = Clock::now();
  Model m;
  std::vector<int> tetFace;
  m.mesh = fe::tetrahedralize(cage.surface, mesh, &tetFace);
  m.tetPart.resize(tetFace.size());
  for (size_t t = 0; t < tetFace.size(); ++t) m.tetPart[t] = cage.facePart[tetFace[t]];
  if (cage.labelTets) cage.labelTets(m.mesh, m.tetPart);
  m.secondsMesh = since(t0);
  return m;
}

std::string ChestLine::describe() const {
  return "lower sternum end " + mm(std::abs(depth)) + " mm " + (depth >= 0 ? "behind" : "in front of") + " the chest line between " +
         pointText(right) + " and " + pointText(left);
}

ChestLine chestLine(const CageSurface& cage, const std::vector<Landmark>& lms, const Placement& pl) {
  checkRadii(pl);
  const Vector3d end = lowerSternumEnd(lms, pl, "the chest line is measured there");
  const Vector3d dir = pl.direction.normalized();
  const auto& V = cage.surface.V;
  // 1. the sternum's anterior surface near its lower end
  std::optional<Vector3d> front;
  for (size_t f = 0; f < cage.surface.F.size(); ++f)
    if (cage.surface.faceTissue[f] == int(Tissue::Sternum))
      for (int v : cage.surface.F[f])
        if ((V[v] - end).norm() <= pl.sternumLoadRadius && (!front || dir.dot(V[v]) > dir.dot(*front))) front = V[v];
  if (!front)
    throw InputError("No sternum surface lies within " + mm(pl.sternumLoadRadius) + " mm of the lower sternum end " + pointText(end) +
                     ": the chest line depth is measured from the sternum's anterior surface there.");
  // 2. the most anterior cage point on each side of the sternum, in a slab around the lower end's level
  std::optional<Vector3d> side[2];
  for (size_t f = 0; f < cage.surface.F.size(); ++f) {
    if (cage.facePart[f] == kVertebralColumn || cage.surface.faceTissue[f] == int(Tissue::Sternum)) continue;
    for (int v : cage.surface.F[f]) {
      if (std::abs(V[v].z() - end.z()) > kChestLineSlab) continue;
      const double dx = V[v].x() - end.x();
      if (std::abs(dx) <= kChestLineGap) continue;
      auto& best = side[dx > 0 ? 1 : 0];  // +x: the patient's left
      if (!best || dir.dot(V[v]) > dir.dot(*best)) best = V[v];
    }
  }
  for (int k = 0; k < 2; ++k)
    if (!side[k])
      throw InputError(std::string("No rib or cartilage lies ") + (k ? "left" : "right") + " of the lower sternum end " + pointText(end) +
                       " within " + mm(kChestLineSlab) + " mm of its level: the chest line cannot be drawn; give the target elevation.");
  // 3. the line between the two points, where it passes the sternum; the depth along the force direction
  ChestLine c;
  c.right = *side[0];
  c.left = *side[1];
  c.sternumFront = *front;
  const double t = (front->x() - c.right.x()) / (c.left.x() - c.right.x());
  c.depth = dir.dot(c.right + t * (c.left - c.right)) - dir.dot(*front);
  return c;
}

std::string Target::describe() const {
  std::string s = mm(elevation) + " mm, " + (fromChestLine ? "from the model: " : "as given");
  if (!chest) return s + (fromChestLine ? "" : " (no chest line: the cage has no ribs beside the lower sternum end)");
  return s + (fromChestLine ? "" : " (") + chest->describe() + (fromChestLine ? "" : ")");
}

Target resolveTarget(const CageSurface& cage, const std::vector<Landmark>& lms, const Options& opt) {
  Target t;
  if (opt.targetFromChestLine) {
    t.chest = chestLine(cage, lms, opt.place);
    if (!(t.chest->depth > 1.0))
      throw InputError("The target elevation is to come from the model (the chest line), but there is no depression to "
                       "correct: " + t.chest->describe() + ". Give the target elevation (mm).");
    t.elevation = t.chest->depth;
    t.fromChestLine = true;
    return t;
  }
  t.elevation = std::max(0.0, opt.targetElevation);
  try {
    t.chest = chestLine(cage, lms, opt.place);
  } catch (const InputError&) {
    return t;  // no chest line to check against (a test body, a cage without ribs beside the sternum)
  }
  if (t.elevation > 0 && t.chest->depth > 1.0 && t.elevation > t.chest->reach()) {
    std::ostringstream s;
    s << "The target elevation " << mm(t.elevation) << " mm lies beyond what the model reaches: " << t.chest->describe()
      << ", so the reachable targets are (0, " << mm(t.chest->reach()) << "] mm (up to " << kMaxCorrection
      << " times the depth; 0 takes the chest line itself). Lower the target elevation.";
    throw InputError(s.str());
  }
  return t;
}

void validate(const Options& opt) {
  fe::validate(opt.mesh);
  if (!kPoissonRange.contains(opt.nuBone) || !kPoissonRange.contains(opt.nuCartilage))
    throw InputError("Poisson's ratios must lie in " + kPoissonRange.text() + ".");
  if (!kModulusRange.contains(opt.eBone) || !kModulusRange.contains(opt.eCartilage))
    throw InputError("Young's moduli must lie in " + kModulusRange.text() + " MPa: bone about 11500, costal cartilage 11-50.");
  if (!kTargetElevationRange.contains(opt.targetElevation))
    throw InputError("The target elevation must lie in " + kTargetElevationRange.text() +
                     " mm (0: a given force, or the chest line's depth).");
  if (opt.targetElevation <= 0 && !kForceRange.contains(opt.force))
    throw InputError("The elevating force must lie in " + kForceRange.text() + " N.");
  if (!(opt.curveStep > 0)) throw InputError("The force-displacement curve step must be positive (N).");
  if (!kMaxForceRange.contains(opt.maxForce)) throw InputError("The maximum force must lie in " + kMaxForceRange.text() + " N.");
  if (!kToleranceRange.contains(opt.tolerance))
    throw InputError("The calibration tolerance must lie in " + kToleranceRange.text() + " mm.");
}

namespace {

Analysis analyzeModel(const CageSurface& cage, Model model, const std::vector<Landmark>& lms, const Options& given,
                      const Target& target);
}  // namespace

Analysis analyze(const CageSurface& cage, const std::vector<Landmark>& lms, const Options& opt) {
  validate(opt);
  const Target target = resolveTarget(cage, lms, opt);
  if (opt.progress) opt.progress(5, "TetGen (after checking the surface)");
  return analyzeModel(cage, buildModel(cage, opt.mesh), lms, opt, target);
}

Analysis analyze(const CageSurface& cage, const Model& model, const std::vector<Landmark>& lms, const Options& opt) {
  validate(opt);
  return analyzeModel(cage, model, lms, opt, resolveTarget(cage, lms, opt));
}

namespace {

using Curve = std::vector<std::pair<double, double>>;  // (force N, elevation mm)

void report(const Options& opt, int pc, const std::string& what) {
  if (opt.progress) opt.progress(pc, what);
}

// the solves of one analysis: the model's solver, its linear solve at unit force, the options, the force
// direction, and the analysis they fill in
struct Solves {
  fe::Solver& solver;
  const fe::Result& unit;
  const Options& opt;
  const Vector3d dir;
  Analysis& a;
};

// the analysis of a model before any solve: the target, the tets and their parts
Analysis analysisOf(Model model, const Target& target) {
  Analysis a;
  a.target = target;
  a.mesh = std::move(model.mesh);
  a.tetPart = std::move(model.tetPart);
  a.secondsMesh = model.secondsMesh;
  return a;
}

// the linear solve at unit force: the sternum's compliance along the force direction, which must be positive
fe::Result linearPreSolve(fe::Solver& solver, Analysis& a, const Vector3d& dir) {
  fe::Result lin1;
  try {
    lin1 = solver.solveLinear(1.0);
  } catch (const SolverFailure& e) {  // the same kind, the message with the slivers that may cause it
    throw SolverFailure(std::string(e.what()) + slivers(a));
  } catch (const InputError& e) {
    throw InputError(std::string(e.what()) + slivers(a));
  }
  a.linearCompliance = elevationOf(lin1.u, a, dir);
  if (!(a.linearCompliance > 0))
    throw InputError("The sternum does not move along the force direction under the elevating force (compliance " +
                     std::to_string(a.linearCompliance) + " mm/N): check the direction and the load placement.");
  return lin1;
}

// small strain: the solve at F is F times the unit-force solve (forces and prescribed displacements both
// scale with the load), von Mises stress and equivalent strain |F| times theirs
fe::Result linearAt(const Solves& s, double F, Curve* curve) {
  fe::Result r = s.unit;
  r.u *= F;
  for (double& v : r.vonMises) v *= std::abs(F);
  for (double& e : r.eqStrain) e *= std::abs(F);
  if (curve) {
    curve->assign(1, {0.0, 0.0});
    for (double f = s.opt.curveStep; f < F - 1e-9; f += s.opt.curveStep) curve->push_back({f, s.a.linearCompliance * f});
    curve->push_back({F, elevationOf(r.u, s.a, s.dir)});
  }
  return r;
}

// the Newton options of a solve that records each iteration into a.newtonHistory (increments numbered on
// from the solves before)
fe::NewtonOptions withHistory(const fe::NewtonOptions& o, Analysis& a) {
  fe::NewtonOptions no = o;
  const int first = a.newtonHistory.empty() ? 0 : a.newtonHistory.back().increment + 1;
  no.onIteration = [&a, first, user = o.onIteration](const fe::NewtonIteration& it) {
    a.newtonHistory.push_back(it);
    a.newtonHistory.back().increment += first;
    if (user) user(it);
  };
  return no;
}

// the nonlinear solve at F, its increments stopping at every curveStep; each converged increment is
// observed and goes into the curve
fe::Result nonlinearAt(Solves& s, double F, Curve* curve, const fe::Observer& observe) {
  Analysis& a = s.a;
  fe::NewtonOptions no = withHistory(s.opt.newton, a);
  no.stops.clear();
  for (double f = s.opt.curveStep; f < F - 1e-9; f += s.opt.curveStep) no.stops.push_back(f / F);
  no.loadSteps = std::max(no.loadSteps, static_cast<int>(std::ceil(F / s.opt.curveStep)));
  Curve pts{{0.0, 0.0}};
  no.onIncrement = [&](double lam, const Eigen::VectorXd& u) {
    pts.push_back({lam * F, elevationOf(u, a, s.dir)});
    if (observe) observe(pts.back().first, pts.back().second);
  };
  fe::Result r = s.solver.solveNonlinear(no, F);
  ++a.nonlinearSolves;
  a.newtonIterations += r.newtonIterations;
  a.factorizations += r.factorizations;
  if (curve) *curve = pts;  // every converged increment: the curveStep multiples and the steps between
  return r;
}

// one solve at force F; records the curve at every curveStep when `curve` is given
fe::Result solveAt(Solves& s, double F, Curve* curve, const fe::Observer& observe) {
  if (!s.opt.nonlinear) return linearAt(s, F, curve);
  return nonlinearAt(s, F, curve, observe);
}

// displacement control: the force Fe, the load factor found, must be positive and within the maximum force
void checkControlledForce(const Options& opt, double force) {
  if (!(force > 0))
    throw InputError("Calibration: the sternum reaches the target only under a force <= 0 (" + mm(force, 2) +
                     " N) along the force direction; check the force direction and the load placement.");
  if (force > opt.maxForce) {
    std::ostringstream s;
    s << "No force up to " << opt.maxForce << " N reaches the target displacement " << opt.targetElevation << " mm (it takes "
      << force << " N). Lower the target or raise the maximum force.";
    throw SolverFailure(s.str());
  }
}

// one solve: the sternal patch's mean displacement along the force direction is stepped to the target
// (steps of about curveStep N at the linear compliance), Fe is the load factor of the unit-force problem
void calibrateByDisplacement(Solves& s) {
  Analysis& a = s.a;
  const Options& opt = s.opt;
  const Vector3d& dir = s.dir;
  report(opt, 30, "Driving the sternum to " + mm(opt.targetElevation) + " mm");
  Eigen::VectorXd w = Eigen::VectorXd::Zero(3 * a.mesh.numNodes());
  for (int n : a.sternumNodes) w.segment<3>(3 * n) = dir / double(a.sternumNodes.size());
  fe::NewtonOptions no = withHistory(opt.newton, a);
  no.stops.clear();
  no.loadSteps = std::max(no.loadSteps, static_cast<int>(std::ceil(opt.targetElevation / (a.linearCompliance * opt.curveStep))));
  a.curve.assign(1, {0.0, 0.0});
  no.onIncrement = [&](double F, const Eigen::VectorXd& u) { a.curve.push_back({F, elevationOf(u, a, dir)}); };
  try {
    a.result = s.solver.solveControlled(w, opt.targetElevation, no);
  } catch (const fe::NewtonDidNotConverge& e) {
    const auto& last = a.curve.back();
    std::ostringstream m;
    m << "No converged state reaches the target displacement " << opt.targetElevation << " mm: driving the sternum up, "
      << "the nonlinear solve stops converging beyond " << last.second << " mm at " << last.first << " N (" << e.what()
      << "). Lower the target, or check the model where it deforms most (an element inverting at the load).";
    throw SolverFailure(m.str());
  }
  ++a.nonlinearSolves;
  a.newtonIterations += a.result.newtonIterations;
  a.factorizations += a.result.factorizations;
  a.force = a.result.loadFactor;
  const double d = elevationOf(a.result.u, a, dir);
  checkControlledForce(opt, a.force);
  fe::CalibrationResult c;
  c.force = a.force;
  c.displacement = d;
  c.evaluations = 1;
  c.history.emplace_back(a.force, d);
  a.calibration = c;
}

// a search over the force (calibrateForce), one solve per trial force; the result is the solve at the force found
void calibrateByForce(Solves& s) {
  Analysis& a = s.a;
  const Options& opt = s.opt;
  fe::CalibrationOptions co;
  co.tolerance = opt.tolerance;
  co.maxForce = opt.maxForce;
  co.initialForce = std::min(opt.targetElevation / a.linearCompliance, opt.maxForce);
  co.maxEvaluations = 12;
  fe::Result last;
  Curve lastCurve;
  int k = 0;
  auto disp = [&](double F, const fe::Observer& observe) {
    report(opt, std::min(90, 20 + 15 * k++), "Calibrating the force: Fe = " + mm(F) + " N");
    last = solveAt(s, F, &lastCurve, observe);
    a.force = F;
    return elevationOf(last.u, a, s.dir);
  };
  a.calibration = fe::calibrateForce(disp, opt.targetElevation, co);
  if (std::abs(a.force - a.calibration->force) > 1e-9 * a.calibration->force) {  // last evaluation not the answer
    last = solveAt(s, a.calibration->force, &lastCurve, {});
    a.force = a.calibration->force;
  }
  a.result = std::move(last);
  a.curve = std::move(lastCurve);
}

// no target: the solve at the given force
void solveGivenForce(Solves& s) {
  report(s.opt, 30, "Solving");
  s.a.force = s.opt.force;
  s.a.result = solveAt(s, s.opt.force, &s.a.curve, {});
}

// nodes where two tissues meet (rib and cartilage, cartilage and sternum): the stiffness changes about
// 1000-fold across them, and at the corner such a junction makes with the free surface the stress of a
// linear model is singular, so the stress of the tets touching them grows as the mesh is refined
std::vector<char> tissueJunctions(const fe::TetMesh& mesh) {
  std::vector<int> nodeTissue(mesh.nodes.size(), -1);
  std::vector<char> junction(mesh.nodes.size(), 0);
  for (int t = 0; t < mesh.numTets(); ++t)
    for (int k = 0; k < mesh.nodesPerTet(); ++k) {
      int& nt = nodeTissue[mesh.tets[t][k]];
      if (nt >= 0 && nt != mesh.tissue[t]) junction[mesh.tets[t][k]] = 1;
      nt = mesh.tissue[t];
    }
  return junction;
}

// where tet t lies: its centroid, tissue, part and distance to its rib's joint (none for t < 0)
Location locate(const Analysis& a, const std::vector<Landmark>& lms, int t) {
  Location L;
  if (t < 0) return L;
  L.tet = t;
  L.p = a.mesh.centroid(t);
  L.tissue = a.mesh.tissue[t];
  L.part = a.tetPart[t];
  if (auto j = findLandmark(lms, L.part)) L.distanceToJoint = (*j - L.p).norm();
  return L;
}

// the nodal stress and strain, the maxima over all tets and per tissue, and the peaks away from the supports
// and load patches (where nodal forces make the stress singular) with where they lie
void locatePeaks(Analysis& a, const std::vector<Landmark>& lms) {
  a.nodalStress = fe::averageToNodes(a.mesh, a.result.vonMises);
  a.nodalStrain = fe::averageToNodes(a.mesh, a.result.eqStrain);
  const std::vector<char> special = supportAndLoadNodes(a);
  const std::vector<char> junction = tissueJunctions(a.mesh);
  int iS = -1, iE = -1, iB = -1;
  for (int t = 0; t < a.mesh.numTets(); ++t) {
    a.maxStressAll = std::max(a.maxStressAll, a.result.vonMises[t]);
    a.maxStrainAll = std::max(a.maxStrainAll, a.result.eqStrain[t]);
    if (a.mesh.tissue[t] == int(Tissue::Cartilage)) a.maxStrainCartilage = std::max(a.maxStrainCartilage, a.result.eqStrain[t]);
    else a.maxStrainBone = std::max(a.maxStrainBone, a.result.eqStrain[t]);
    if (touches(a.mesh, t, special)) continue;
    if (iS < 0 || a.result.vonMises[t] > a.result.vonMises[iS]) iS = t;
    if (iE < 0 || a.result.eqStrain[t] > a.result.eqStrain[iE]) iE = t;
    if (!touches(a.mesh, t, junction) && (iB < 0 || a.result.vonMises[t] > a.result.vonMises[iB])) iB = t;
  }
  if (iS >= 0) a.maxStress = a.result.vonMises[iS], a.maxStressAt = locate(a, lms, iS);
  if (iE >= 0) a.maxStrain = a.result.eqStrain[iE], a.maxStrainAt = locate(a, lms, iE);
  if (iB >= 0) a.maxStressBody = a.result.vonMises[iB], a.maxStressBodyAt = locate(a, lms, iB);
}

// the supports and loads placed on the model, the linear pre-solve, the calibration (by displacement control,
// by a force search, or none: the given force), the peaks
Analysis analyzeModel(const CageSurface& cage, Model model, const std::vector<Landmark>& lms, const Options& given,
                      const Target& target) {
  Options opt = given;
  opt.targetElevation = target.elevation;
  Analysis a = analysisOf(std::move(model), target);
  place(cage, lms, opt.place, a);
  const Vector3d dir = opt.place.direction.normalized();
  a.components = checkComponents(a.mesh, a.tetPart, a.fixedNodes, meanEdgeLength(cage.surface));

  auto t0 = Clock::now();
  report(opt, 15, "Factorising (CHOLMOD)");
  fe::Problem prob = problemAt(a, opt, 1.0);  // unit Fe; the solves scale it
  fe::Solver solver(prob);
  const fe::Result lin1 = linearPreSolve(solver, a, dir);
  Solves solves{solver, lin1, opt, dir, a};
  if (opt.targetElevation > 0 && opt.nonlinear && opt.calibration == CalibrationMethod::DisplacementControl)
    calibrateByDisplacement(solves);
  else if (opt.targetElevation > 0)
    calibrateByForce(solves);
  else
    solveGivenForce(solves);
  a.elevation = elevationOf(a.result.u, a, dir);
  a.secondsSolve = since(t0);

  report(opt, 95, "Stress and strain");
  locatePeaks(a, lms);
  report(opt, 100, "Done");
  return a;
}
}  // namespace

std::vector<char> supportAndLoadNodes(const Analysis& a) {
  std::vector<char> flag(a.mesh.nodes.size(), 0);
  for (int n : a.fixedNodes) flag[n] = 1;
  for (int n : a.sternumNodes) flag[n] = 1;
  for (int n : a.secondSternumNodes) flag[n] = 1;
  for (int n : a.sternoclavicularNodes) flag[n] = 1;
  for (const auto& v : a.supportNodes)
    for (int n : v) flag[n] = 1;
  return flag;
}

bool touches(const fe::TetMesh& m, int t, const std::vector<char>& nodes) {
  for (int k = 0; k < m.nodesPerTet(); ++k)
    if (nodes[m.tets[t][k]]) return true;
  return false;
}

std::vector<PathSample> strainAlongRib(const Analysis& a, int side, int rib, double binWidth) {
  if (!(binWidth > 0)) throw InputError("The rib path bin width must be positive (mm).");
  const int part = ribPart(side, rib);
  // midline: mean x of the sternum tets; the rib's sternal end: its most medial tet
  double xs = 0;
  int ns = 0;
  int medial = -1;
  const double sgn = side == 1 ? -1.0 : 1.0;  // right = -x
  for (int t = 0; t < a.mesh.numTets(); ++t) {
    if (a.mesh.tissue[t] == int(Tissue::Sternum)) xs += a.mesh.centroid(t).x(), ++ns;
    if (a.tetPart[t] == part && (medial < 0 || sgn * a.mesh.centroid(t).x() < sgn * a.mesh.centroid(medial).x())) medial = t;
  }
  if (medial < 0) throw InputError("The model has no " + partName(int(Tissue::Bone), part) + ".");
  if (ns) xs /= ns;
  const double zj = a.mesh.centroid(medial).z();
  std::map<int, PathSample> bins;
  std::map<int, std::array<int, 4>> counts;  // tets per tissue in each bin: the bin's tissue is the majority
  for (int t = 0; t < a.mesh.numTets(); ++t) {
    const Vector3d c = a.mesh.centroid(t);
    const bool onPart = a.tetPart[t] == part;
    const bool sternumHere = a.mesh.tissue[t] == int(Tissue::Sternum) && std::abs(c.z() - zj) <= 5.0 && sgn * (c.x() - xs) >= 0;
    if (!onPart && !sternumHere) continue;
    const double d = std::max(0.0, sgn * (c.x() - xs));
    const int b = static_cast<int>(d / binWidth);
    auto& s = bins[b];
    s.distance = (b + 0.5) * binWidth;
    s.meanStrain += a.result.eqStrain[t];
    s.meanStress += a.result.vonMises[t];
    s.maxStrain = std::max(s.maxStrain, a.result.eqStrain[t]);
    counts[b][std::clamp(a.mesh.tissue[t], 0, 3)]++;
    ++s.tets;
  }
  std::vector<PathSample> out;
  for (auto& [b, s] : bins) {
    s.meanStrain /= s.tets;
    s.meanStress /= s.tets;
    const auto& c = counts[b];
    s.tissue = static_cast<int>(std::max_element(c.begin(), c.end()) - c.begin());
    out.push_back(s);
  }
  return out;
}

}  // namespace pectus::nuss
