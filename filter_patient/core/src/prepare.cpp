#include "pectus/patient/prepare.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <exception>
#include <fstream>
#include <map>
#include <numeric>
#include <regex>
#include <set>
#include <sstream>
#include <tuple>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <vcg/complex/allocate.h>

#include "pectus/mesh_simplify.h"
#include "pectus/errors.h"
#include "pectus/format.h"
#include "pectus/patient/shape_classify.h"
#include "pectus/patient/solid_grid.h"
#include "pectus/patient/soup.h"
#include "marching_cubes.h"

namespace pectus::patient {

namespace {
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

std::string mm(double v, int digits = 1) { return fixedText(v, digits); }
std::string at(const Vec3& p) { return "(" + mm(p.x()) + ", " + mm(p.y()) + ", " + mm(p.z()) + ")"; }
std::string sideName(int side) { return side == 2 ? "left" : "right"; }

// ---------------------------------------------------------------------------------------------------
// 1. the structures, by name
struct Structure {
  std::string name;  // layer name, or "<layer> piece k"
  NameClass cls;
  Soup soup;
  int layer = -1;  // the layer of `all` it comes from (its solid gives the surface's crossings)
};

std::vector<std::string> words(const std::string& name) {
  std::string n;
  for (char c : name) n += std::isalnum(static_cast<unsigned char>(c)) ? char(std::tolower(static_cast<unsigned char>(c))) : ' ';
  // split letters from digits: "rib3" -> "rib 3", "t12" -> "t 12"
  std::string m;
  for (std::size_t i = 0; i < n.size(); ++i) {
    if (i > 0 && n[i] != ' ' && n[i - 1] != ' ' && bool(std::isdigit(static_cast<unsigned char>(n[i]))) !=
                                                       bool(std::isdigit(static_cast<unsigned char>(n[i - 1]))))
      m += ' ';
    m += n[i];
  }
  std::istringstream s(m);
  std::vector<std::string> w;
  for (std::string x; s >> x;) w.push_back(x);
  return w;
}

// ---------------------------------------------------------------------------------------------------
// 4. the solids on one grid
// A piece of a fused bone layer shorter than this share of its longest piece (the length of a piece: its box's
// diagonal) is no rib: a fragment of a vertebra, of a scapula or of a rib cut by the field of view. A 12th rib is
// about half as long as the longest; a split-off process, a tenth.
constexpr double kMinRibShare = 0.25;
// The ribs are cut off the vertebral column this far (mm) beyond the column's band, square: a rib running along
// the cut (the 1st rib beside its vertebra) would otherwise keep a sheet of bone in the cut's plane, which the tet
// mesh fills with sub-millimetre tets
constexpr double kCutTrim = 1.5;

// ---------------------------------------------------------------------------------------------------
// 3. the frame
struct Frame {
  Mat3 R = Mat3::Identity();  // rows: patient's left, anterior, superior (in the scaled input frame)
  std::string how;
  bool superiorOpen = false;  // the superior sign is still to be decided from the ribs
};

// Each rib runs down from its vertebral end to its front end: true if most ribs do so in the current
// frame (z superior), false if most run up (the frame is upside down).
bool ribsRunDown(const std::vector<std::pair<Vec3, Vec3>>& ends) {
  int down = 0, up = 0;
  for (const auto& [back, front] : ends) (back.z() > front.z() ? down : up) += 1;
  return down >= up;
}

Frame findFrame(const std::vector<Structure>& all, const PrepareOptions& opt, double size) {
  Frame fr;
  if (opt.frame == FrameMode::Model) return {Mat3::Identity(), "stated: the project frame (+x left, +y anterior, +z superior)"};
  if (opt.frame == FrameMode::RAS) {
    fr.R << -1, 0, 0, 0, 1, 0, 0, 0, 1;
    fr.how = "stated: RAS (x right, y anterior, z superior)";
    return fr;
  }
  if (opt.frame == FrameMode::LPS) {
    fr.R << 1, 0, 0, 0, -1, 0, 0, 0, 1;
    fr.how = "stated: LPS (x left, y posterior, z superior)";
    return fr;
  }
  Soup sternum, bone;
  for (const auto& s : all) {
    if (s.cls.kind == Kind::Sternum) append(sternum, s.soup);
    if (s.cls.kind == Kind::Rib || s.cls.kind == Kind::Bone || s.cls.kind == Kind::Vertebra) append(bone, s.soup);
  }
  const Vec3 cS = centroid(sternum), cB = centroid(bone);
  Vec3 a = cS - cB;
  if (a.norm() < 0.05 * size)
    throw InputError("Cannot find the anatomical frame: the sternum's centre lies at the centre of the bone (" + at(cS) +
                     "), so the anterior direction is unknown. Check that the sternum layer holds the sternum, or state "
                     "the frame (parameter 'Frame': RAS, LPS or the project frame).");
  a.normalize();
  // long axis: the sternum's principal direction, square to anterior
  Vec3 mean = Vec3::Zero();
  for (const auto& p : sternum.V) mean += p;
  mean /= double(sternum.V.size());
  Mat3 C = Mat3::Zero();
  for (const auto& p : sternum.V) C += (p - mean) * (p - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Mat3> eig(C);
  Vec3 s = eig.eigenvectors().col(2);
  s = (s - s.dot(a) * a);
  if (s.norm() < 1e-6)
    throw InputError("Cannot find the anatomical frame: the sternum's long axis points to the back. State the frame "
                     "(parameter 'Frame').");
  s.normalize();
  // CT exports are axis-aligned: snap both axes to the file's axes when each is within 30 degrees of one
  auto snap = [](const Vec3& v, int& axis) {
    v.cwiseAbs().maxCoeff(&axis);
    return std::abs(v[axis]) > std::cos(30.0 * M_PI / 180.0);
  };
  int ia = 0, is = 0;
  if (snap(a, ia) && snap(s, is) && ia != is) {
    a = Vec3::Unit(ia) * (a[ia] > 0 ? 1 : -1);
    s = Vec3::Unit(is) * (s[is] > 0 ? 1 : -1);
    fr.how = "from the anatomy, snapped to the file's axes";
  } else {
    fr.how = "from the anatomy (not aligned with the file's axes)";
  }
  // superior: from the rib numbers when the names carry them (rib 1 on top), else from the ribs' slope
  // (a rib runs down from its vertebral end to the front: the anterior bone lies lower)
  double numZ = 0, num = 0;
  std::vector<std::pair<double, double>> nz;
  for (const auto& st : all)
    if (st.cls.kind == Kind::Rib && st.cls.number > 0) nz.push_back({double(st.cls.number), centroid(st.soup).dot(s)});
  bool fromNames = false;
  if (nz.size() >= 2) {
    double mn = 0, mz = 0;
    for (auto [n, z] : nz) mn += n, mz += z;
    mn /= double(nz.size()), mz /= double(nz.size());
    for (auto [n, z] : nz) numZ += (n - mn) * (z - mz), num += (n - mn) * (n - mn);
    fromNames = num > 0 && std::abs(numZ) > 0;
  }
  if (fromNames) {
    if (numZ > 0) s = -s;
    fr.how += "; superior from the rib numbers";
  } else {
    fr.superiorOpen = true;  // decided from the ribs' slope once the ribs are separated (superiorFromSlope)
  }
  // the patient's left: scanner frames are right-handed (RAS, LPS): left = superior x anterior (names
  // with sides are checked once the superior direction is final: leftFromNames)
  const Vec3 l = s.cross(a);
  fr.R.row(0) = l.transpose();
  fr.R.row(1) = a.transpose();
  fr.R.row(2) = s.transpose();
  return fr;
}

// ---------------------------------------------------------------------------------------------------
// 4. the vertebral column inside a bone layer
// The column: the bone thicker than a rib (what stays of a bone layer's large pieces where a ball of kColumnCore mm
// fits inside: ribs, scapulae and processes are thinner) on the midline behind the cage's middle, running at least
// kColumnHeight mm. It needs no other part of the anatomy: whatever the scan's field of view, the ribs beside the
// column and the specks around it, the thick bone on the midline is the vertebral bodies.
constexpr double kColumnCore = 4.0, kColumnHeight = 40.0;

// ---------------------------------------------------------------------------------------------------
// 8. landmarks
struct Anatomy {
  std::map<int, std::vector<Vec3>> rib;  // part -> bone vertices
  std::vector<Vec3> sternum, cartilage, junction;  // junction: vertices shared by sternum and cartilage faces
  std::vector<Vec3> spine;               // vertebral column points (from vertebra layers or the cut)
};

Anatomy anatomyOf(const CMeshO& cage) {
  Anatomy an;
  const auto lab = readFaceLabels(cage);
  std::vector<int> tissueOfVertex(cage.vert.size(), 0);  // bit set of tissues touching the vertex
  for (std::size_t f = 0; f < cage.face.size(); ++f) {
    if (cage.face[f].IsD()) continue;
    for (int k = 0; k < 3; ++k) tissueOfVertex[std::size_t(vcg::tri::Index(cage, cage.face[f].cV(k)))] |= 1 << lab->tissue[f];
  }
  std::vector<char> seen(cage.vert.size(), 0);
  for (std::size_t f = 0; f < cage.face.size(); ++f) {
    if (cage.face[f].IsD()) continue;
    for (int k = 0; k < 3; ++k) {
      const std::size_t v = std::size_t(vcg::tri::Index(cage, cage.face[f].cV(k)));
      const Vec3 p = toEigen(cage.vert[v].cP());
      if (lab->tissue[f] == int(Tissue::Bone)) an.rib[lab->part[f]].push_back(p);
      if (seen[v]) continue;
      seen[v] = 1;
      if (lab->tissue[f] == int(Tissue::Sternum)) an.sternum.push_back(p);
      if (lab->tissue[f] == int(Tissue::Cartilage)) an.cartilage.push_back(p);
      const int both = (1 << int(Tissue::Sternum)) | (1 << int(Tissue::Cartilage));
      if ((tissueOfVertex[v] & both) == both) an.junction.push_back(p);
    }
  }
  return an;
}

Vec3 mean(const std::vector<Vec3>& v) {
  Vec3 c = Vec3::Zero();
  for (const auto& p : v) c += p;
  return v.empty() ? c : Vec3(c / double(v.size()));
}

// What the landmarks are placed from, and the landmarks placed so far. `given`: the codes of the user's points.
struct LandmarkPlacer {
  const Anatomy& an;
  double x0, yMid;  // the midline's x, the y of the cage's middle
  const std::set<int>& given;
  std::vector<std::string>& log;
  std::vector<Landmark> lms;
  std::map<int, Vec3> cvj;  // the costovertebral joints placed, by code
};

// A landmark that cannot be placed is refused unless the user gives it (then the user's point, placed later,
// stands for it).
void cannotPlace(LandmarkPlacer& c, int code, const std::string& what, const std::string& why) {
  if (c.given.count(code)) {
    c.log.push_back("landmark " + std::to_string(code) + " (" + what + ") cannot be placed automatically (" + why +
                    "): the user's point stands for it");
    return;
  }
  throw InputError("Cannot place the landmark '" + what + "' (code " + std::to_string(code) + "): " + why + ". Pick it "
                   "with Edit > PickPoints on the input layers and give the .pp file (parameter 'Picked points'), the "
                   "point named " + std::to_string(code) + ".");
}

// costovertebral joints: the rib head, the centre of the rib's vertebral end. The heads line up along the
// spine: its axis (x0, yAxis) is where the ribs' medial-most posterior points lie (their median y); each
// rib's head is its point nearest that axis in the transverse plane, and the joint the centroid of the
// rib's surface within one joint radius (6 mm, as the FE analysis fixes) of it.
void placeJoints(LandmarkPlacer& c) {
  const double x0 = c.x0, yMid = c.yMid;
  auto medialMost = [&](const std::vector<Vec3>& pts) {
    const Vec3* best = nullptr;
    for (const auto& p : pts)
      if (p.y() < yMid && (!best || std::abs(p.x() - x0) < std::abs(best->x() - x0))) best = &p;
    return best;
  };
  std::vector<double> medialY;
  for (const auto& [part, pts] : c.an.rib)
    if (part >= 101 && part <= 212)
      if (const Vec3* m = medialMost(pts)) medialY.push_back(m->y());
  std::nth_element(medialY.begin(), medialY.begin() + long(medialY.size() / 2), medialY.end());
  const double yAxis = medialY.empty() ? yMid : medialY[medialY.size() / 2];
  for (const auto& [part, pts] : c.an.rib) {
    if (part < 101 || part > 212) continue;
    if (!medialMost(pts)) {
      cannotPlace(c, part, "costovertebral joint of the " + sideName(part / 100) + " rib " + std::to_string(part % 100),
                  "the rib has no part behind the cage's middle");
      continue;
    }
    const Vec3* tip = nullptr;
    auto toAxis = [&](const Vec3& p) { return std::hypot(p.x() - x0, p.y() - yAxis); };
    for (const auto& p : pts)
      if (p.y() < yMid && (!tip || toAxis(p) < toAxis(*tip))) tip = &p;
    std::vector<Vec3> end;
    for (const auto& p : pts)
      if ((p - *tip).norm() < 6.0) end.push_back(p);
    c.cvj[part] = mean(end);
    c.lms.push_back({part, c.cvj[part]});
  }
}

struct SternumEnds {
  double zLo, zHi;    // the sternum's lowest and highest z
  Vec3 lower, upper;  // its ends: the means of its points within 3 mm of them
};

// the sternum's ends
SternumEnds placeSternumEnds(LandmarkPlacer& c) {
  if (c.an.sternum.empty())  // every other landmark is placed from the sternum: no picked point stands for it
    throw InputError("Cannot place the landmarks: the joined cage has no sternum faces. Check the sternum's layer.");
  double zLo = 1e300, zHi = -1e300;
  for (const auto& p : c.an.sternum) zLo = std::min(zLo, p.z()), zHi = std::max(zHi, p.z());
  std::vector<Vec3> lo, hi;
  for (const auto& p : c.an.sternum) {
    if (p.z() < zLo + 3) lo.push_back(p);
    if (p.z() > zHi - 3) hi.push_back(p);
  }
  const SternumEnds e{zLo, zHi, mean(lo), mean(hi)};
  c.lms.push_back({kSternumLowerEnd, e.lower});
  c.lms.push_back({kSternumUpperEnd, e.upper});
  return e;
}

// the spine's front at height z: the vertebral column's most anterior midline point, else the joints'
double spineFront(const LandmarkPlacer& c, double z, bool& measured) {
  double y = -1e300;
  for (const auto& p : c.an.spine)
    if (std::abs(p.x() - c.x0) < 10 && std::abs(p.z() - z) < 5) y = std::max(y, p.y());
  measured = y > -1e299;
  if (measured) return y;
  double best = 1e300, yb = 0;
  for (const auto& [part, p] : c.cvj)
    if (std::abs(p.z() - z) < best) best = std::abs(p.z() - z), yb = p.y();
  return yb;
}

struct Deepest {
  bool found;
  double y, z;
};

// deepest funnel point: the sternum level with the smallest distance between its front and the spine; the
// vertebra at its level
Deepest placeDeepest(LandmarkPlacer& c, const SternumEnds& e) {
  const double L = e.zHi - e.zLo, x0 = c.x0;
  double bestAp = 1e300, zDeep = 0.5 * (e.zLo + e.zHi), yDeep = 0;
  for (double z = e.zLo + 0.1 * L; z <= e.zHi - 0.1 * L; z += 2.0) {
    double yf = -1e300;
    for (const auto& p : c.an.sternum)
      if (std::abs(p.x() - x0) < 8 && std::abs(p.z() - z) < 1.0) yf = std::max(yf, p.y());
    if (yf < -1e299) continue;
    bool m = false;
    const double ap = yf - spineFront(c, z, m);
    if (ap < bestAp) bestAp = ap, zDeep = z, yDeep = yf;
  }
  const bool deepFound = bestAp < 1e299;
  if (!deepFound) cannotPlace(c, kFunnelDeepest, "deepest point of the funnel", "the sternum has no front surface near its midline");
  else c.lms.push_back({kFunnelDeepest, Vec3(x0, yDeep, zDeep)});
  bool spineMeasured = false;
  const double ySpine = spineFront(c, zDeep, spineMeasured);
  if (spineMeasured && deepFound) c.lms.push_back({kVertebraAtDeepest, Vec3(x0, ySpine, zDeep)});
  else if (!deepFound) c.log.push_back("landmark 503 (vertebra at the deepest level) not placed: the deepest point is the user's");
  else c.log.push_back("no vertebral column in the input: landmark 503 (vertebra at the deepest level) not placed; the pectus "
                       "index then measures to the costovertebral joints' line");
  return {deepFound, yDeep, zDeep};
}

// bar exits at the mid-axillary line: halfway between the lateral-most points of ribs s and s+1; returns how many
int placeBarExits(LandmarkPlacer& c) {
  auto lateral = [&](int part, Vec3& out) {
    const auto it = c.an.rib.find(part);
    if (it == c.an.rib.end()) return false;
    double dmax = 0;
    for (const auto& p : it->second) dmax = std::max(dmax, std::abs(p.x() - c.x0));
    std::vector<Vec3> side;
    for (const auto& p : it->second)
      if (std::abs(p.x() - c.x0) > dmax - 3) side.push_back(p);
    out = mean(side);
    return true;
  };
  int exits = 0;
  for (int side = 1; side <= 2; ++side)
    for (int s = 1; s <= 9; ++s) {  // codes 600 + 10*side + s hold one digit of space
      Vec3 a, b;
      if (lateral(100 * side + s, a) && lateral(100 * side + s + 1, b)) c.lms.push_back({barExitLandmark(side, s), 0.5 * (a + b)}), ++exits;
    }
  return exits;
}

// diaphragm dome height: the lowest sternocostal junction (the xiphisternal level); lung apex: top of rib 1;
// each midway between the sternum and the spine. Gives their heights (zApex -1e300: none).
void placeDomeAndApex(LandmarkPlacer& c, const SternumEnds& e, double& zDome, double& zApex) {
  zDome = e.zLo + 0.15 * (e.zHi - e.zLo);
  if (!c.an.junction.empty()) {
    zDome = 1e300;
    for (const auto& p : c.an.junction) zDome = std::min(zDome, p.z());
  } else {
    c.log.push_back("the cartilages do not meet the sternum: the diaphragm dome height is taken 15 % of the sternum's "
                    "length above its lower end");
  }
  zApex = -1e300;
  for (int side = 1; side <= 2; ++side)
    if (const auto it = c.an.rib.find(100 * side + 1); it != c.an.rib.end())
      for (const auto& p : it->second) zApex = std::max(zApex, p.z());
  if (zApex < -1e299) cannotPlace(c, kLungApex, "lung apex", "there is no first rib");
  bool m = false;
  c.lms.push_back({kDiaphragmDome, Vec3(c.x0, 0.5 * (e.lower.y() + spineFront(c, zDome, m)), zDome)});
  if (zApex > -1e299) c.lms.push_back({kLungApex, Vec3(c.x0, 0.5 * (e.upper.y() + spineFront(c, zApex, m)), zApex)});
}

// the landmarks: the costovertebral joints, the sternum's ends, the funnel's deepest point and the vertebra at
// its level, the bar exits, the diaphragm dome and the lung apex; what was placed goes into the log. `given`:
// the codes of the user's points (cannotPlace).
std::vector<Landmark> placeLandmarks(const Anatomy& an, double x0, double yMid, const std::set<int>& given,
                                     std::vector<std::string>& log) {
  LandmarkPlacer c{an, x0, yMid, given, log, {}, {}};
  placeJoints(c);
  const SternumEnds e = placeSternumEnds(c);
  const Deepest deep = placeDeepest(c, e);
  const int exits = placeBarExits(c);
  double zDome = 0, zApex = 0;
  placeDomeAndApex(c, e, zDome, zApex);
  log.push_back("landmarks: " + std::to_string(c.cvj.size()) + " costovertebral joints, sternum ends at " + at(e.lower) +
                " and " + at(e.upper) + ", deepest point " +
                (deep.found ? "at " + at(Vec3(x0, deep.y, deep.z)) : std::string("the user's")) + ", " +
                std::to_string(exits) + " bar exits, diaphragm dome z " + mm(zDome) + ", lung apex z " +
                (zApex > -1e299 ? mm(zApex) : std::string("the user's")) + " (before centring)");
  return std::move(c.lms);
}

// relabels the faces of `m` from the nearest face of the labelled surface (pts, tris, labels)
void relabel(CMeshO& m, const CMeshO& from) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Tri = K::Triangle_3;
  using Prim = CGAL::AABB_triangle_primitive<K, std::vector<Tri>::const_iterator>;
  using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Prim>>;
  const auto lab = readFaceLabels(from);
  std::vector<Tri> tris;
  std::vector<std::size_t> faceOf;
  auto P = [](const Point3m& p) { return K::Point_3(p[0], p[1], p[2]); };
  for (std::size_t f = 0; f < from.face.size(); ++f)
    if (!from.face[f].IsD()) tris.emplace_back(P(from.face[f].cP(0)), P(from.face[f].cP(1)), P(from.face[f].cP(2))), faceOf.push_back(f);
  Tree tree(tris.begin(), tris.end());
  tree.accelerate_distance_queries();
  std::vector<int> tissue(m.face.size()), part(m.face.size());
  for (std::size_t f = 0; f < m.face.size(); ++f) {
    if (m.face[f].IsD()) continue;
    const Point3m c = (m.face[f].cP(0) + m.face[f].cP(1) + m.face[f].cP(2)) / 3.0f;
    const auto hit = tree.closest_point_and_primitive(P(c));
    const std::size_t src = faceOf[std::size_t(hit.second - tris.begin())];
    tissue[f] = lab->tissue[src], part[f] = lab->part[src];
  }
  writeFaceLabels(m, tissue, part);
}

// The cartilages' faces take the part of the nearest rib face (the vertebral column is no rib)
void partsOfCartilage(const Soup& u, const std::vector<int>& tissue, std::vector<int>& part) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Tri = K::Triangle_3;
  using Prim = CGAL::AABB_triangle_primitive<K, std::vector<Tri>::const_iterator>;
  using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Prim>>;
  auto P = [&](int v) { return K::Point_3(u.V[std::size_t(v)].x(), u.V[std::size_t(v)].y(), u.V[std::size_t(v)].z()); };
  std::vector<Tri> ribs;
  std::vector<int> ribPartOf;
  for (std::size_t f = 0; f < u.F.size(); ++f)
    if (tissue[f] == int(Tissue::Bone) && part[f] != kVertebralColumn)
      ribs.emplace_back(P(u.F[f][0]), P(u.F[f][1]), P(u.F[f][2])), ribPartOf.push_back(part[f]);
  if (ribs.empty()) return;
  Tree tree(ribs.begin(), ribs.end());
  tree.accelerate_distance_queries();
  for (std::size_t f = 0; f < u.F.size(); ++f) {
    if (tissue[f] != int(Tissue::Cartilage)) continue;
    const Vec3 c = (u.V[std::size_t(u.F[f][0])] + u.V[std::size_t(u.F[f][1])] + u.V[std::size_t(u.F[f][2])]) / 3.0;
    const auto hit = tree.closest_point_and_primitive(K::Point_3(c.x(), c.y(), c.z()));
    part[f] = ribPartOf[std::size_t(hit.second - ribs.begin())];
  }
}

// "N connected pieces: the cage (...), right rib 11, ...": what each piece of the joined surface holds, the largest
// first (the user sees which ribs float and what came loose)
std::string describePieces(const Soup& s, const FaceLabels& lab) {
  std::vector<int> faceComponent;
  std::vector<std::pair<std::size_t, std::set<int>>> list(std::size_t(Topology(s).components(faceComponent)));
  for (std::size_t f = 0; f < s.F.size(); ++f) {  // per piece: faces, parts (tissue * 1000 + part)
    auto& p = list[std::size_t(faceComponent[f])];
    ++p.first;
    p.second.insert(lab.tissue[f] * 1000 + lab.part[f]);
  }
  std::stable_sort(list.begin(), list.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::string out = std::to_string(list.size()) + " connected piece" + (list.size() == 1 ? "" : "s");
  for (std::size_t i = 0; i < list.size(); ++i) {
    std::set<int> tissues;
    std::string what;
    for (int code : list[i].second) {
      tissues.insert(code / 1000);
      const int part = code % 1000, side = part / 100, rib = part % 100;
      if (code / 1000 == int(Tissue::Bone) && (side == 1 || side == 2) && rib >= 1 && rib <= 24)
        what += (what.empty() ? "" : ", ") + sideName(side) + " rib " + std::to_string(rib);
    }
    if (tissues.count(int(Tissue::Sternum))) what = "the cage";
    else if (what.empty()) what = "costal cartilage";
    else if (tissues.count(int(Tissue::Cartilage))) what += " with cartilage";
    out += (i ? ", " : ": ") + what;
  }
  return out;
}

// The pieces of a solid (6-connected components of `mask`): their boxes and points
struct Pieces {
  std::vector<std::int32_t> comp;   // per point of the solid's box: 1 + piece, 0 none
  std::vector<std::size_t> count;   // points per piece
  std::vector<Box3i> box;           // per piece, in the solid's box
  std::vector<char> reaches;        // per piece: it reaches the column's cut band
};

// The preparation's state, as each step hands it on to the next: the structures (in the project frame's axes
// once the frame is found), the vertebral column's points, the frame, and the Log.
class Preparation {
 public:
  Preparation(const PrepareOptions& o, const std::function<void(int, const char*)>& progress) : opt(o), progress_(progress) {
    if (!kMinVolumeRange.contains(opt.minVolume))
      throw InputError("parameters: the minimum volume must lie in " + kMinVolumeRange.text() + " mm^3");
    if (!kGridStepRange.contains(opt.gridStep))
      throw InputError("parameters: the grid step must lie in " + kGridStepRange.text() + " mm");
    if (!kEdgeLengthRange.contains(opt.edgeLength) || (opt.edgeLength > 0 && opt.edgeLength < kMinEdgeLength))
      throw InputError("parameters: the target edge length must be 0 or lie in " +
                       ParamRange{kMinEdgeLength, kEdgeLengthRange.hi}.text() + " mm");
  }
  void classify(const std::vector<InputLayer>& layers);  ///< 1. each layer's kind from its name, else its shape
  void toMillimetres();                                  ///< 2. the units
  void orient();                                         ///< 3. the anatomical frame's axes
  void separate();                                       ///< 4. solids, the spine cut, fragments, what is not cage
  void settleSuperiorAndLeft();                          ///< 3, finished on the separated ribs
  void numberRibs();                                     ///< 5. rib numbers and sides
  void join(CMeshO& cage);                               ///< 6. one labelled surface, decimated
  void placeAndCentre(CMeshO& cage);                     ///< 7. landmarks, the origin, the user's points
  PrepareResult res;

 private:
  void prog(int pc, const char* what) const { if (progress_) progress_(pc, what); }
  /// a point of the grid's frame (mm, the frame's axes before `flip`) in the input layers' frame and units
  Vec3 toInput(const Vec3& p) const { return fr.R.transpose() * (flip * p) / scale; }
  void classifyUnknownByShape(std::vector<Structure>& unknown);  ///< 1, for the layers whose names say nothing
  void checkTheCage(std::size_t layers) const;  ///< 1, finished: a sternum, cartilage and ribs are there
  std::string whatTheScanHolds() const;         ///< 1, for a refusal: the layers' extent and anatomy
  Vec3 vertebralEnd(const Soup& rib) const;  ///< the rib's point nearest the midline, behind the cage's middle
  void takeApart(std::size_t layer);         ///< 4, for one layer: its pieces kept, cut or left out
  double cutColumn(std::size_t layer, std::vector<std::uint8_t>& mask);  ///< 4, a bone layer's column
  std::size_t trimAtTheCut(const Solid& so, double band, std::vector<std::uint8_t>& mask, std::vector<std::int32_t>& column) const;
  template <class Large>
  double columnHalfWidth(const Solid& so, const Pieces& p, const Large& large) const;  ///< 4
  Pieces piecesOf(const Solid& so, const std::vector<std::uint8_t>& mask, double band) const;  ///< 4
  void bridgeAlongTheLength(const std::string& name, const Solid& so, std::vector<std::uint8_t>& mask);  ///< 4, the sternum
  /// 4. the surface of the points of layer's solid (local box indices) for which keep() holds, in the box sub
  template <class Keep>
  Soup solidSurface(std::size_t layer, const Box3i& sub, const Keep& keep) const;
  void keep(Structure s, std::size_t layer, const Box3i& sub, const std::vector<std::int32_t>& comp, std::int32_t id);
  void dropUnanchored();                              ///< 6. pieces that join no rib left out
  void unite(bool withColumn, OwnedMesh& out) const;  ///< 6. the surface of the kept structures' points, labelled
  void decimate(OwnedMesh& joinedSurface, CMeshO& cage);  ///< 6. to the edge length

  const PrepareOptions& opt;
  std::function<void(int, const char*)> progress_;
  std::vector<std::string>& log = res.log;
  std::vector<Structure> all;   // recognised layers, then (kept) the structures of the model
  std::vector<Structure> kept;
  std::vector<Vec3> spine;      // vertebral column points: vertebra layers and the cut-away bone
  double diag = 0, scale = 1;   // the input's size (its units) and the factor to mm
  Frame fr;
  Mat3 flip = Mat3::Identity(); // the turns of settleSuperiorAndLeft, after the grid was laid
  double x0 = 0, yMid = 0;      // the sternum's midline; halfway between the back of the cage and the sternum
  Grid grid;                    // one grid for every structure, in the frame's axes (before `flip`)
  std::vector<Solid> solids;    // per layer of `all`
  std::vector<std::uint16_t> owner;  // per grid point: 1 + the index in `kept` of the structure it belongs to
  OwnedMesh joined;             // the labelled surface of ribs, cartilages and sternum, before decimation
};

void Preparation::classify(const std::vector<InputLayer>& layers) {
  prog(2, "classifying the layers");
  std::vector<Structure> unknown;
  for (const auto& l : layers) {
    Structure s{l.name, classifyName(l.name), surfaceOf(*l.mesh, kFiniteFaces)};
    if (s.soup.empty()) {
      log.push_back("'" + l.name + "': no faces, left out");
      continue;
    }
    if (s.cls.kind == Kind::NotCage) {
      log.push_back("'" + l.name + "': not part of the rib cage, left out");
      ++res.dropped;
      continue;
    }
    weld(s.soup);
    (s.cls.kind == Kind::Unknown ? unknown : all).push_back(std::move(s));
  }
  if (!unknown.empty()) classifyUnknownByShape(unknown);
  for (const auto& s : all)
    log.push_back("'" + s.name + "': " +
                  (s.cls.kind == Kind::Rib ? (s.cls.number ? sideName(s.cls.side) + " rib " + std::to_string(s.cls.number)
                                                           : std::string("rib (side and number from its place)"))
                   : s.cls.kind == Kind::Cartilage ? std::string("costal cartilage")
                   : s.cls.kind == Kind::Sternum ? std::string("sternum")
                   : s.cls.kind == Kind::Vertebra ? std::string(opt.spine == SpineMode::Keep ? "vertebral column (kept as the fixed support)" : "vertebral column (frame and landmarks, not in the model)")
                                                  : std::string("bone (ribs, maybe fused to the spine)")) +
                  ", " + std::to_string(s.soup.F.size()) + " faces");
  checkTheCage(layers.size());
}

void Preparation::classifyUnknownByShape(std::vector<Structure>& unknown) {
  std::vector<LayerToClassify> in;
  for (const auto& s : all) in.push_back({s.name, &s.soup, s.cls});
  for (const auto& s : unknown) in.push_back({s.name, &s.soup, s.cls});
  log.push_back(std::to_string(unknown.size()) + " layer" + (unknown.size() > 1 ? "s" : "") + " named like no rib cage "
                "structure: classified by their shape");
  const auto cls = classifyByShape(in, log);
  const std::size_t named = all.size();
  for (std::size_t i = 0; i < unknown.size(); ++i) {
    const NameClass& c = cls[named + i];
    if (c.kind == Kind::NotCage || c.kind == Kind::Unknown) {
      ++res.dropped;
      continue;
    }
    unknown[i].cls = {c.kind, 0, 0};  // side and number of a rib come from its place (numberRibs)
    all.push_back(std::move(unknown[i]));
  }
}

// What the recognised layers hold and where, for the refusals of a partial scan: "The layers span z = 92.8 to
// 182.8 (file units) and hold right ribs 7-12, left ribs 7-12, costal cartilage, 'vertebrae_T11' and 'vertebrae_T12'."
std::string Preparation::whatTheScanHolds() const {
  Eigen::AlignedBox3d box;
  std::map<int, std::set<int>> ribs;
  std::vector<std::string> vertebrae;
  std::set<std::string> other;
  for (const auto& s : all) {
    for (const auto& p : s.soup.V) box.extend(p);
    if (s.cls.kind == Kind::Rib && s.cls.number) ribs[s.cls.side].insert(s.cls.number);
    else if (s.cls.kind == Kind::Vertebra) vertebrae.push_back(s.name);
    else other.insert(s.cls.kind == Kind::Cartilage ? "costal cartilage" : s.cls.kind == Kind::Sternum ? "sternum"
                      : s.cls.kind == Kind::Bone ? "bone" : "ribs");
  }
  const auto range = [](const std::set<int>& n) {
    std::string r;
    for (auto it = n.begin(); it != n.end();) {
      auto end = it;
      while (std::next(end) != n.end() && *std::next(end) == *end + 1) ++end;
      r += (r.empty() ? "" : ", ") + std::to_string(*it) + (end != it ? "-" + std::to_string(*end) : "");
      it = std::next(end);
    }
    return r;
  };
  std::vector<std::string> parts;
  for (const auto& [side, n] : ribs) parts.push_back((side == 2 ? "left ribs " : side == 1 ? "right ribs " : "ribs ") + range(n));
  for (const auto& o : other) parts.push_back(o);
  if (vertebrae.size() > 6) parts.push_back(std::to_string(vertebrae.size()) + " vertebrae");
  for (std::size_t i = 0; vertebrae.size() <= 6 && i < vertebrae.size(); ++i) parts.push_back("'" + vertebrae[i] + "'");
  std::string held;
  for (std::size_t i = 0; i < parts.size(); ++i) held += (i ? (i + 1 == parts.size() ? " and " : ", ") : "") + parts[i];
  if (box.isEmpty()) return "";
  return " The layers span z = " + mm(box.min().z()) + " to " + mm(box.max().z()) + " (file units)" +
         (held.empty() ? std::string(".") : " and hold " + held + ".") +
         (ribs.empty() || *std::min_element(ribs.begin(), ribs.end(), [](const auto& a, const auto& b) {
                            return *a.second.begin() < *b.second.begin(); })->second.begin() <= 1
              ? std::string()
              : " The scan looks partial (its top ends below the first ribs): the analysis needs the whole rib cage.");
}

void Preparation::checkTheCage(std::size_t layers) const {
  auto count = [&](Kind k) { return std::count_if(all.begin(), all.end(), [&](const Structure& s) { return s.cls.kind == k; }); };
  if (all.empty())
    throw InputError("None of the " + std::to_string(layers) + " layers is named like a rib cage structure: name them "
                     "as TotalSegmentator does ('rib_left_1' ... 'rib_right_12', 'costal_cartilages', 'sternum', "
                     "'vertebrae_T1' ...) or 'bone', 'cartilage', 'sternum'.");
  if (!count(Kind::Sternum))
    throw InputError("No sternum: none of the layers is named 'sternum' (or 'manubrium', 'xiphoid'). Import the sternum's "
                     "segmentation, or rename its layer." + whatTheScanHolds());
  if (!count(Kind::Cartilage))
    throw InputError("No costal cartilage: none of the layers is named like 'costal_cartilages' or 'cartilage'. The "
                     "cartilages join the ribs to the sternum; segment them (TotalSegmentator's 'costal_cartilages')." +
                     whatTheScanHolds());
  if (!count(Kind::Rib) && !count(Kind::Bone))
    throw InputError("No ribs: none of the layers is named like 'rib_left_1', 'ribs' or 'bone'." + whatTheScanHolds());
}

void Preparation::toMillimetres() {
  Eigen::AlignedBox3d box;
  for (const auto& s : all)
    for (const auto& p : s.soup.V) box.extend(p);
  diag = box.diagonal().norm();
  scale = 1;
  if (opt.units == Units::Metres || (opt.units == Units::Auto && diag < 3)) scale = 1000;
  else if (opt.units == Units::Centimetres || (opt.units == Units::Auto && diag < 60)) scale = 10;
  log.push_back("units: " + std::string(scale == 1000 ? "metres" : scale == 10 ? "centimetres" : "millimetres") +
                (opt.units == Units::Auto ? " (the structures span " + mm(diag, 3) + " units)" : std::string(" (stated)")) +
                (scale != 1 ? ", scaled to mm" : ""));
  if (scale * diag < 100 || scale * diag > 1500)
    throw InputError("The structures span " + mm(scale * diag) + " mm, not a rib cage (150-700 mm): state the units "
                     "(parameter 'Units').");
  for (auto& s : all)
    for (auto& p : s.soup.V) p *= scale;
}

void Preparation::orient() {
  fr = findFrame(all, opt, scale * diag);
  for (auto& s : all) transform(s.soup, fr.R, Vec3::Zero());
  log.push_back("frame " + fr.how);
  Soup sternumAll;
  for (const auto& s : all)
    if (s.cls.kind == Kind::Sternum) append(sternumAll, s.soup);
  x0 = centroid(sternumAll).x();
  Eigen::AlignedBox3d cageBox;
  for (const auto& s : all)
    for (const auto& p : s.soup.V) cageBox.extend(p);
  yMid = 0.5 * (cageBox.min().y() + centroid(sternumAll).y());
}

// Every structure becomes a solid on one grid (solid_grid.h): what a surface's defects would make ambiguous
// (holes, duplicate faces, self-intersections, nested marrow shells, slivers) does not change which grid points
// are inside. The solids are then taken apart: a fused bone layer loses its vertebral column, and its pieces
// are ribs, loose bone or fragments; the structures claim their points in the order sternum, ribs, bone,
// cartilage, vertebrae (where two overlap, the first keeps the point).
void Preparation::separate() {
  prog(10, "the structures' solids on one grid");
  Eigen::AlignedBox3d box;
  for (const auto& s : all)
    for (const auto& p : s.soup.V) box.extend(p);
  grid.h = opt.gridStep;
  grid.origin = box.min();
  for (int a = 0; a < 3; ++a) grid.box.n[std::size_t(a)] = int(std::ceil(box.sizes()[a] / grid.h)) + 1;
  solids.assign(all.size(), Solid{});
#pragma omp parallel for schedule(dynamic)
  for (int i = 0; i < int(all.size()); ++i) solids[std::size_t(i)] = solidify(all[std::size_t(i)].soup, grid);
  owner.assign(grid.box.size(), 0);
  const auto rank = [](Kind k) { return k == Kind::Sternum ? 0 : k == Kind::Rib ? 1 : k == Kind::Bone ? 2 : k == Kind::Cartilage ? 3 : 4; };
  std::vector<std::size_t> order(all.size());
  std::iota(order.begin(), order.end(), std::size_t(0));
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return rank(all[a].cls.kind) < rank(all[b].cls.kind); });
  for (std::size_t k = 0; k < order.size(); ++k) {
    prog(10 + int(15 * k / order.size()), "separating the structures");
    takeApart(order[k]);
  }
  log.push_back("grid: " + mm(grid.h, 2) + " mm steps, " + std::to_string(grid.box.n[0]) + " x " + std::to_string(grid.box.n[1]) +
                " x " + std::to_string(grid.box.n[2]) + " points");
}

template <class Keep>
Soup Preparation::solidSurface(std::size_t layer, const Box3i& sub, const Keep& keep) const {
  const Solid& so = solids[layer];
  const auto in = [&](int a, int b, int c) {  // a, b, c: the sub-box's point less one (padded)
    const int la = sub.lo[0] + a - 1, lb = sub.lo[1] + b - 1, lc = sub.lo[2] + c - 1;
    if (la < sub.lo[0] || lb < sub.lo[1] || lc < sub.lo[2] || la >= sub.lo[0] + sub.n[0] || lb >= sub.lo[1] + sub.n[1] ||
        lc >= sub.lo[2] + sub.n[2])
      return false;
    return bool(keep(so.box.index(la, lb, lc)));
  };
  Soup out;
  marchCubes(
      sub.n[0] + 2, sub.n[1] + 2, sub.n[2] + 2, in,
      [&](int a, int b, int c, int axis) {
        const int i = so.box.lo[0] + sub.lo[0] + a - 1, j = so.box.lo[1] + sub.lo[1] + b - 1, k = so.box.lo[2] + sub.lo[2] + c - 1;
        Vec3 q = grid.point(i, j, k);
        q[axis] += grid.h * so.exit(i, j, k, axis, in(a, b, c));
        return q;
      },
      out.V, [&](int, int, int, const std::array<int, 3>& f) { out.F.push_back(f); });
  return out;
}

void Preparation::keep(Structure st, std::size_t layer, const Box3i& sub, const std::vector<std::int32_t>& comp, std::int32_t id) {
  const Solid& so = solids[layer];
  if (kept.size() + 1 >= 65535) throw InputError("More than 65,534 structures to keep: raise the minimum volume.");
  st.layer = int(layer);
  st.soup = solidSurface(layer, sub, [&](std::size_t p) { return comp[p] == id; });
  const std::uint16_t me = std::uint16_t(kept.size() + 1);
  for (int c = sub.lo[2]; c < sub.lo[2] + sub.n[2]; ++c)
    for (int b = sub.lo[1]; b < sub.lo[1] + sub.n[1]; ++b)
      for (int a = sub.lo[0]; a < sub.lo[0] + sub.n[0]; ++a) {
        if (comp[so.box.index(a, b, c)] != id) continue;
        const int i = so.box.lo[0] + a, j = so.box.lo[1] + b, k = so.box.lo[2] + c;
        if (!grid.box.contains(i, j, k)) continue;
        std::uint16_t& o = owner[grid.box.index(i, j, k)];
        if (!o) o = me;
      }
  kept.push_back(std::move(st));
}

// A segmentation often parts the manubrium from the body of the sternum (their joint is cartilage, not bone): the
// gaps along the sternum's length, up to kSternumGap, are filled, so that the sternum is one piece as in the body.
constexpr double kSternumGap = 4.0;

void Preparation::bridgeAlongTheLength(const std::string& name, const Solid& so, std::vector<std::uint8_t>& mask) {
  const int longest = int(kSternumGap / grid.h);
  std::size_t filled = 0;
  for (int b = 0; b < so.box.n[1]; ++b)
    for (int a = 0; a < so.box.n[0]; ++a) {
      int last = -1;  // the last inside point along the column
      for (int c = 0; c < so.box.n[2]; ++c) {
        if (!mask[so.box.index(a, b, c)]) continue;
        if (last >= 0 && c - last > 1 && c - last - 1 <= longest)
          for (int g = last + 1; g < c; ++g) mask[so.box.index(a, b, g)] = 1, ++filled;
        last = c;
      }
    }
  if (filled)
    log.push_back("'" + name + "': gaps along its length up to " + mm(kSternumGap, 0) + " mm bridged (the manubriosternal joint), " +
                  mm(double(filled) * grid.h * grid.h * grid.h / 1000, 2) + " cm3 added");
}


Pieces Preparation::piecesOf(const Solid& so, const std::vector<std::uint8_t>& mask, double band) const {
  Pieces p;
  p.count = components6(so.box.n, mask, p.comp);
  p.box.assign(p.count.size(), Box3i{so.box.n, {0, 0, 0}});
  p.reaches.assign(p.count.size(), 0);
  std::vector<std::array<int, 3>> hi(p.count.size(), {-1, -1, -1});
  for (int c = 0; c < so.box.n[2]; ++c)
    for (int b = 0; b < so.box.n[1]; ++b)
      for (int a = 0; a < so.box.n[0]; ++a) {
        const std::int32_t id = p.comp[so.box.index(a, b, c)];
        if (!id) continue;
        const std::size_t k = std::size_t(id - 1);
        p.box[k].lo = {std::min(p.box[k].lo[0], a), std::min(p.box[k].lo[1], b), std::min(p.box[k].lo[2], c)};
        hi[k] = {std::max(hi[k][0], a), std::max(hi[k][1], b), std::max(hi[k][2], c)};
        const Vec3 q = grid.point(so.box.lo[0] + a, so.box.lo[1] + b, so.box.lo[2] + c);
        if (band > 0 && q.y() < yMid && std::abs(q.x() - x0) < band + 1.5 * grid.h) p.reaches[k] = 1;
      }
  for (std::size_t k = 0; k < p.box.size(); ++k)
    for (int a = 0; a < 3; ++a) p.box[k].n[std::size_t(a)] = hi[k][std::size_t(a)] - p.box[k].lo[std::size_t(a)] + 1;
  return p;
}

// The half-width of a bone layer's vertebral column (0: none): the opening of its large pieces by a ball of
// kColumnCore mm (the points within that radius of a point at least that deep inside), the opened pieces that
// lie on the midline behind the cage's middle, and the median over their heights of their extent from the
// midline (the rib heads widen them at their own levels only).
template <class Large>
double Preparation::columnHalfWidth(const Solid& so, const Pieces& p, const Large& large) const {
  const auto& n = so.box.n;
  std::vector<std::uint8_t> outside(p.comp.size()), core(p.comp.size()), opened(p.comp.size());
  for (std::size_t q = 0; q < outside.size(); ++q) outside[q] = !large(q);
  const double r2 = (kColumnCore / grid.h) * (kColumnCore / grid.h);
  const std::vector<float> depth = squaredDistance(n, outside);
  for (std::size_t q = 0; q < core.size(); ++q) core[q] = depth[q] > r2;
  const std::vector<float> toCore = squaredDistance(n, core);
  for (std::size_t q = 0; q < opened.size(); ++q) opened[q] = large(q) && toCore[q] <= r2;
  std::vector<std::int32_t> comp;
  const auto count = components6(n, opened, comp);
  std::vector<char> onMidline(count.size(), 0);
  const auto at = [&](int a, int b, int c) { return grid.point(so.box.lo[0] + a, so.box.lo[1] + b, so.box.lo[2] + c); };
  for (int c = 0; c < n[2]; ++c)
    for (int b = 0; b < n[1]; ++b)
      for (int a = 0; a < n[0]; ++a)
        if (const std::int32_t id = comp[so.box.index(a, b, c)]; id && at(a, b, c).y() < yMid && std::abs(at(a, b, c).x() - x0) < grid.h)
          onMidline[std::size_t(id - 1)] = 1;
  std::vector<double> widest;  // per height the column reaches: its extent from the midline
  for (int c = 0; c < n[2]; ++c) {
    double w = -1;
    for (int b = 0; b < n[1]; ++b)
      for (int a = 0; a < n[0]; ++a)
        if (const std::int32_t id = comp[so.box.index(a, b, c)]; id && onMidline[std::size_t(id - 1)] && at(a, b, c).y() < yMid)
          w = std::max(w, std::abs(at(a, b, c).x() - x0));
    if (w >= 0) widest.push_back(w);
  }
  if (double(widest.size()) * grid.h < kColumnHeight) return 0;
  std::nth_element(widest.begin(), widest.begin() + long(widest.size() / 2), widest.end());
  return widest[widest.size() / 2] + 0.5 * grid.h;
}

// Where a rib runs along the cut's plane (the 1st rib, beside its vertebra), the cut leaves a sheet of bone one or
// two grid steps thick: the tet mesh would fill it with slivers, and the joint fixed on it would carry a stress
// ten times the posterior ribs'. Within kCutTrim beyond the cut, the bone thinner than kSheet is opened away
// (the points not within kSheet / 2 of a point at least that deep inside) and goes with the column. Returns how
// many points.
constexpr double kSheet = 2.4;

std::size_t Preparation::trimAtTheCut(const Solid& so, double band, std::vector<std::uint8_t>& mask,
                                      std::vector<std::int32_t>& column) const {
  const auto& n = so.box.n;
  std::vector<std::uint8_t> outside(mask.size());
  for (std::size_t q = 0; q < mask.size(); ++q) outside[q] = !mask[q];
  const double r = 0.5 * kSheet / grid.h;
  const std::vector<float> depth = squaredDistance(n, outside);
  std::vector<std::uint8_t> core(mask.size());
  for (std::size_t q = 0; q < mask.size(); ++q) core[q] = depth[q] > r * r;
  const std::vector<float> toCore = squaredDistance(n, core);
  std::size_t trimmed = 0;
  for (int c = 0; c < n[2]; ++c)
    for (int b = 0; b < n[1]; ++b)
      for (int a = 0; a < n[0]; ++a) {
        const std::size_t q = so.box.index(a, b, c);
        if (!mask[q] || toCore[q] <= r * r) continue;
        const Vec3 x = grid.point(so.box.lo[0] + a, so.box.lo[1] + b, so.box.lo[2] + c);
        if (x.y() < yMid && std::abs(x.x() - x0) < band + kCutTrim) mask[q] = 0, column[q] = 1, ++trimmed;
      }
  return trimmed;
}

// The vertebral column of a bone layer (columnHalfWidth) taken out of `mask`, into a column structure when it is
// kept. Returns the half-width of the cut band (0: no column).
double Preparation::cutColumn(std::size_t layer, std::vector<std::uint8_t>& mask) {
  const Structure& s = all[layer];
  const Solid& so = solids[layer];
  const double h3 = grid.h * grid.h * grid.h;
  const Pieces p = piecesOf(so, mask, 0);
  const auto large = [&](std::size_t q) { return p.comp[q] > 0 && double(p.count[std::size_t(p.comp[q] - 1)]) * h3 >= opt.minVolume; };
  const double rCut = columnHalfWidth(so, p, large);
  if (rCut <= 0) return 0;
  const double band = rCut + kCutTrim;
  const Box3i whole{{0, 0, 0}, so.box.n};
  for (const auto& q : solidSurface(layer, whole, large).V)
    if (q.y() < yMid && std::abs(q.x() - x0) < rCut) spine.push_back(q);
  std::vector<std::int32_t> column(mask.size(), 0);
  std::size_t removed = 0;
  for (int c = 0; c < so.box.n[2]; ++c)
    for (int b = 0; b < so.box.n[1]; ++b)
      for (int a = 0; a < so.box.n[0]; ++a) {
        const std::size_t q = so.box.index(a, b, c);
        const Vec3 x = grid.point(so.box.lo[0] + a, so.box.lo[1] + b, so.box.lo[2] + c);
        if (mask[q] && large(q) && x.y() < yMid && std::abs(x.x() - x0) < band) mask[q] = 0, column[q] = 1, ++removed;
      }
  removed += trimAtTheCut(so, band, mask, column);
  const bool keepColumn = opt.spine == SpineMode::Keep;
  log.push_back("'" + s.name + "': vertebral column found (posterior midline, " + mm(2 * rCut) + " mm wide): cut at the "
                "costovertebral joints, the ribs' ends square at " + mm(band) + " mm from the midline (" +
                mm(double(removed) * h3 / 1000, 1) + " cm3 removed)" + (keepColumn ? "; the column is kept as the fixed support" : ""));
  if (keepColumn) keep({s.name + " vertebral column", {Kind::Vertebra, 0, 0}, {}, -1}, layer, whole, column, 1);
  return band;
}

// One layer's solid taken apart: fragments dropped; a bone layer's column cut away and its pieces kept as ribs
// or left out; any other layer's pieces kept together as its structure.
void Preparation::takeApart(std::size_t layer) {
  Structure& s = all[layer];
  const Solid& so = solids[layer];
  const double h3 = grid.h * grid.h * grid.h;
  const Box3i whole{{0, 0, 0}, so.box.n};
  std::vector<int> faceComponent;
  const int pieces0 = Topology(s.soup).components(faceComponent);
  log.push_back("'" + s.name + "': " + std::to_string(pieces0) + " piece" + (pieces0 == 1 ? "" : "s") + " -> a solid of " +
                mm(double(so.count()) * h3 / 1000, 2) + " cm3" +
                (so.capped > 0 ? " (" + std::to_string(so.capped) + " hole" + (so.capped == 1 ? "" : "s") + " capped)" : std::string()) +
                (so.duplicates > 0 ? " (" + std::to_string(so.duplicates) + " duplicate faces ignored)" : std::string()));
  std::vector<std::uint8_t> mask = so.in;
  if (s.cls.kind == Kind::Vertebra) {
    const Soup surface = solidSurface(layer, whole, [&](std::size_t p) { return so.in[p] != 0; });
    spine.insert(spine.end(), surface.V.begin(), surface.V.end());
    if (opt.spine == SpineMode::Keep) keep({s.name, s.cls, {}, -1}, layer, whole, std::vector<std::int32_t>(mask.begin(), mask.end()), 1);
    return;
  }
  if (s.cls.kind == Kind::Sternum) bridgeAlongTheLength(s.name, so, mask);
  const double band = s.cls.kind == Kind::Bone ? cutColumn(layer, mask) : 0;
  const Pieces p = piecesOf(so, mask, band);
  const auto lengthOf = [&](std::size_t k) { return grid.h * Vec3(p.box[k].n[0] - 1, p.box[k].n[1] - 1, p.box[k].n[2] - 1).norm(); };
  double longest = 0;  // of the bone layer's pieces that may be ribs
  for (std::size_t k = 0; k < p.count.size(); ++k)
    if (double(p.count[k]) * h3 >= opt.minVolume && (band <= 0 || p.reaches[k])) longest = std::max(longest, lengthOf(k));
  int fragments = 0, loose = 0;
  double fragmentVolume = 0;
  std::vector<char> together(p.count.size(), 0);  // the pieces kept as the layer's one structure
  for (std::size_t k = 0; k < p.count.size(); ++k) {
    const double v = double(p.count[k]) * h3;
    if (v < opt.minVolume) {
      ++fragments, fragmentVolume += v;
      continue;
    }
    if (s.cls.kind != Kind::Bone) {
      together[k] = 1;
      continue;
    }
    const Box3i& bx = p.box[k];
    const Vec3 lo = grid.point(so.box.lo[0] + bx.lo[0], so.box.lo[1] + bx.lo[1], so.box.lo[2] + bx.lo[2]);
    const Vec3 hi = lo + grid.h * Vec3(bx.n[0] - 1, bx.n[1] - 1, bx.n[2] - 1);
    const double length = lengthOf(k);
    const char* why = band > 0 && !p.reaches[k] ? "does not reach the spine (scapula, clavicle or loose bone)"
                      : length < kMinRibShare * longest ? "is too short for a rib (a fragment of a vertebra, a scapula or a cut rib)"
                                                        : nullptr;
    if (why) {
      ++loose;
      log.push_back("'" + s.name + "': left out a piece of " + mm(v / 1000, 2) + " cm3 at " + at(toInput(0.5 * (lo + hi))) + " (input frame), " +
                    mm(length, 0) + " mm long, that " + why);
      continue;
    }
    keep({s.name + " piece " + std::to_string(kept.size() + 1), {Kind::Rib, 0, 0}, {}, -1}, layer, bx, p.comp, std::int32_t(k + 1));
  }
  if (fragments)
    log.push_back("'" + s.name + "': dropped " + std::to_string(fragments) + " fragments under " + mm(opt.minVolume, 0) + " mm3 (" +
                  mm(fragmentVolume, 0) + " mm3 in all)");
  res.dropped += fragments + loose;
  if (s.cls.kind == Kind::Bone) return;
  if (std::none_of(together.begin(), together.end(), [](char t) { return t; })) {
    log.push_back("'" + s.name + "': nothing left after dropping fragments");
    return;
  }
  std::vector<std::int32_t> mine(p.comp.size(), 0);
  for (std::size_t q = 0; q < mine.size(); ++q) mine[q] = p.comp[q] > 0 && together[std::size_t(p.comp[q] - 1)];
  keep({s.name, s.cls, {}, -1}, layer, whole, mine, 1);
}

Vec3 Preparation::vertebralEnd(const Soup& r) const {
    Vec3 best(0, 0, 0);
    double d = 1e300;
    for (const auto& p : r.V)
      if (p.y() < yMid && std::abs(p.x() - x0) < d) d = std::abs(p.x() - x0), best = p;
    if (d > 1e299)
      for (const auto& p : r.V)
        if (std::abs(p.x() - x0) < d) d = std::abs(p.x() - x0), best = p;
    return best;
}

void Preparation::settleSuperiorAndLeft() {
  if (fr.superiorOpen) {  // superior: where the ribs' vertebral ends are (each rib runs down to the front)
    std::vector<std::pair<Vec3, Vec3>> ends;
    for (const auto& st : kept) {
      if (st.cls.kind != Kind::Rib) continue;
      Vec3 front = st.soup.V.front();
      for (const auto& p : st.soup.V)
        if (p.y() > front.y()) front = p;
      ends.push_back({vertebralEnd(st.soup), front});
    }
    if (!ribsRunDown(ends)) {  // upside down: turn about the anterior axis (keeps the handedness)
      const Mat3 turn = Eigen::Vector3d(-1, 1, -1).asDiagonal();
      for (auto& st : kept) transform(st.soup, turn, Vec3::Zero());
      for (auto& p : spine) p = turn * p;
      fr.R = turn * fr.R;
      flip = turn * flip;
      x0 = -x0;
    }
    log.push_back("superior from the ribs' slope (" + std::to_string(ends.size()) + " ribs: each runs down from its vertebral end)");
  }

  if (opt.frame == FrameMode::Auto) {  // names with sides decide when they disagree with the handedness
    double leftMinusRight = 0;
    for (const auto& st : kept)
      if ((st.cls.kind == Kind::Rib || st.cls.kind == Kind::Cartilage) && st.cls.side)
        leftMinusRight += (st.cls.side == 2 ? 1 : -1) * (centroid(st.soup).x() - x0);
    if (leftMinusRight < 0) {
      const Mat3 mirror = Eigen::Vector3d(-1, 1, 1).asDiagonal();
      for (auto& st : kept) transform(st.soup, mirror, Vec3::Zero());
      for (auto& p : spine) p = mirror * p;
      fr.R = mirror * fr.R;
      flip = mirror * flip;
      x0 = -x0;
      log.push_back("the names put the left ribs on the right of a right-handed scanner frame: the file is mirrored, and "
                    "the names are followed");
    }
  }
}

void Preparation::numberRibs() {
  prog(20, "numbering the ribs");
  std::map<int, std::vector<std::pair<double, Structure*>>> unnamed;  // side -> (end z, rib)
  std::map<int, std::set<int>> named;
  for (auto& s : kept) {
    if (s.cls.kind != Kind::Rib) continue;
    const Vec3 c = centroid(s.soup);
    const int geomSide = c.x() > x0 ? 2 : 1;
    if (s.cls.side && s.cls.side != geomSide)
      log.push_back("'" + s.name + "': named " + sideName(s.cls.side) + " but lies on the " + sideName(geomSide) + " side; the name is kept");
    if (!s.cls.side) s.cls.side = geomSide;
    if (s.cls.number) named[s.cls.side].insert(s.cls.number);
    else unnamed[s.cls.side].push_back({vertebralEnd(s.soup).z(), &s});
  }
  for (auto& [side, list] : unnamed) {
    std::sort(list.begin(), list.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
    if (!named[side].empty()) {
      log.push_back(std::to_string(list.size()) + " unnamed " + sideName(side) + " bone pieces left out: that side's ribs are named");
      for (auto& [z, s] : list) s->cls.kind = Kind::NotCage;
      continue;
    }
    int k = 0;
    for (auto& [z, s] : list) s->cls.number = ++k, named[side].insert(k);
    log.push_back(sideName(side) + " ribs numbered 1-" + std::to_string(k) + " from the top by the height of their vertebral end");
  }
  for (int side = 1; side <= 2; ++side) {
    const auto& n = named[side];
    if (n.empty())
      throw InputError("Ribs on the " + sideName(3 - side) + " side only: the " + sideName(side) + " ribs are missing. Import "
                       "both sides (the analysis needs the whole cage).");
    std::string missing;
    for (int r = 1; r <= std::max(7, *n.rbegin()); ++r)
      if (!n.count(r)) missing += (missing.empty() ? "" : ", ") + std::to_string(r);
    if (!missing.empty())
      throw InputError("Ribs missing on the " + sideName(side) + " side: " + missing + " (found " + std::to_string(n.size()) +
                       "). The analysis needs ribs 1-7 on each side and no gaps; import the missing ribs' segmentations.");
  }
  res.ribsRight = int(named[1].size()), res.ribsLeft = int(named[2].size());
}

// The joined surface is the boundary of the kept structures' grid points, by marching cubes on the one grid:
// closed, 2-manifold and embedded by construction, whatever the structures were. Each face takes the tissue and
// part of the structure whose point is nearest to it; the cartilages take the part of the nearest rib.
void Preparation::unite(bool withColumn, OwnedMesh& out) const {
  const Box3i& B = grid.box;
  const auto at = [&](int i, int j, int k) -> int {  // the structure at grid point (i, j, k), -1 for none
    if (!B.contains(i, j, k)) return -1;
    const int o = owner[B.index(i, j, k)] - 1;
    if (o < 0) return -1;
    const Kind kind = kept[std::size_t(o)].cls.kind;
    return kind == Kind::NotCage || (kind == Kind::Vertebra && !withColumn) ? -1 : o;
  };
  Soup u;
  std::vector<int> faceOf;  // the structure of each face
  marchCubes(
      B.n[0] + 2, B.n[1] + 2, B.n[2] + 2, [&](int a, int b, int c) { return at(a - 1, b - 1, c - 1) >= 0; },
      [&](int a, int b, int c, int axis) {
        const int i = a - 1, j = b - 1, k = c - 1;
        std::array<int, 3> n{i, j, k};
        ++n[std::size_t(axis)];
        const int s0 = at(i, j, k), st = s0 >= 0 ? s0 : at(n[0], n[1], n[2]);
        Vec3 q = grid.point(i, j, k);
        q[axis] += grid.h * solids[std::size_t(kept[std::size_t(st)].layer)].exit(i, j, k, axis, s0 >= 0);
        return q;
      },
      u.V,
      [&](int a, int b, int c, const std::array<int, 3>& f) {
        const Vec3 centre = (u.V[std::size_t(f[0])] + u.V[std::size_t(f[1])] + u.V[std::size_t(f[2])]) / 3.0;
        int best = -1;
        double bd = 1e300;
        for (int corner = 0; corner < 8; ++corner) {
          const int i = a - 1 + (corner & 1), j = b - 1 + ((corner >> 1) & 1), k = c - 1 + ((corner >> 2) & 1);
          const int st = at(i, j, k);
          if (st < 0) continue;
          if (const double d = (grid.point(i, j, k) - centre).squaredNorm(); d < bd) bd = d, best = st;
        }
        u.F.push_back(f);
        faceOf.push_back(best);
      });
  transform(u, flip, Vec3::Zero());  // the turns found after the grid was laid
  std::vector<int> tissue(u.F.size()), part(u.F.size());
  for (std::size_t f = 0; f < u.F.size(); ++f) {
    const Structure& st = kept[std::size_t(faceOf[f])];
    switch (st.cls.kind) {
      case Kind::Rib: tissue[f] = int(Tissue::Bone), part[f] = ribPart(st.cls.side, st.cls.number); break;
      case Kind::Vertebra: tissue[f] = int(Tissue::Bone), part[f] = kVertebralColumn; break;
      case Kind::Sternum: tissue[f] = int(Tissue::Sternum), part[f] = kSternumBody; break;
      default: tissue[f] = int(Tissue::Cartilage), part[f] = 0; break;
    }
  }
  partsOfCartilage(u, tissue, part);
  toMesh(u, out);
  writeFaceLabels(out, tissue, part);
}

// A piece of cartilage or sternum that joins no rib would float in the analysis: a cartilage's end cut off by the
// field of view, or a piece of a structure separated from the rest. Such pieces are left out.
void Preparation::dropUnanchored() {
  const Box3i& B = grid.box;
  std::vector<std::uint8_t> mask(owner.size(), 0);
  for (std::size_t p = 0; p < owner.size(); ++p) {
    if (!owner[p]) continue;
    const Kind k = kept[owner[p] - 1u].cls.kind;
    mask[p] = k == Kind::Rib || k == Kind::Cartilage || k == Kind::Sternum;
  }
  std::vector<std::int32_t> comp;
  const auto count = components6(B.n, mask, comp);
  std::vector<char> anchored(count.size(), 0);
  std::vector<Eigen::AlignedBox3d> where(count.size());
  std::vector<std::set<std::string>> what(count.size());
  for (int c = 0; c < B.n[2]; ++c)
    for (int b = 0; b < B.n[1]; ++b)
      for (int a = 0; a < B.n[0]; ++a) {
        const std::size_t p = B.index(a, b, c);
        if (!comp[p]) continue;
        const Structure& st = kept[owner[p] - 1u];
        const std::size_t k = std::size_t(comp[p] - 1);
        anchored[k] = anchored[k] || st.cls.kind == Kind::Rib;
        where[k].extend(grid.point(a, b, c));
        what[k].insert(st.cls.kind == Kind::Cartilage ? "costal cartilage" : st.cls.kind == Kind::Sternum ? "sternum" : "rib");
      }
  const double h3 = grid.h * grid.h * grid.h;
  for (std::size_t k = 0; k < count.size(); ++k) {
    if (anchored[k]) continue;
    std::string names;
    for (const auto& n : what[k]) names += (names.empty() ? "" : " and ") + n;
    log.push_back("left out a piece of " + names + " of " + mm(double(count[k]) * h3 / 1000, 2) + " cm3 at " +
                  at(toInput(where[k].center())) + " (input frame) that joins no rib (cut off by the field of view, or apart from the rest)");
    ++res.dropped;
  }
  for (std::size_t p = 0; p < owner.size(); ++p)
    if (comp[p] && !anchored[std::size_t(comp[p] - 1)]) owner[p] = 0;
}

void Preparation::join(CMeshO& cage) {
  prog(60, "joining the tissues");
  dropUnanchored();
  unite(false, joined);
  const Soup s = surfaceOf(joined, kFiniteFaces);
  log.push_back("joined on the grid: " + describePieces(s, *readFaceLabels(joined)) + ", " + mm(volume(s) / 1000, 1) + " cm3, " +
                std::to_string(joined.fn) + " faces");
  if (std::none_of(kept.begin(), kept.end(), [](const Structure& st) { return st.cls.kind == Kind::Vertebra; })) {
    decimate(joined, cage);
    return;
  }
  // the landmarks come from the cage without the column, so that they are the same in either spine mode: with
  // the column, the rib ends (and so the costovertebral joints) lie inside it
  prog(70, "joining the tissues and the vertebral column");
  OwnedMesh withColumn;
  unite(true, withColumn);
  log.push_back("with the vertebral column as the fixed support: " + std::to_string(withColumn.fn) + " faces");
  decimate(withColumn, cage);
}

// edges shorter than this share of the edge length are collapsed after the decimation
constexpr double kShortEdge = 0.5;

void Preparation::decimate(OwnedMesh& joinedSurface, CMeshO& cage) {
  prog(75, "decimating");
  cage.Clear();
  copyLabelledMesh(cage, joinedSurface);
  if (!(opt.edgeLength > 0)) return;
  double ar = 0;
  for (const auto& f : cage.face) ar += double(vcg::DoubleArea(f)) / 2;
  const int target = int(ar / (0.433 * opt.edgeLength * opt.edgeLength));
  if (target >= cage.fn) return;
  // in two stages: a retry (where a collapse made faces cross) starts again from its stage's input, so the first
  // stage, from the union's hundreds of thousands of faces, goes to a fine edge where it rarely needs one
  if (4 * target < cage.fn) {
    decimateEmbedded(cage, 4 * target, opt.edgeLength / 2);
    vcg::tri::Allocator<CMeshO>::CompactEveryVector(cage);
  }
  decimateEmbedded(cage, target, opt.edgeLength);
  vcg::tri::Allocator<CMeshO>::CompactEveryVector(cage);
  // Quadric decimation keeps short edges where the surface turns sharply: the cut ends of the ribs at the
  // costovertebral joints, the tissue junctions. TetGen grades its tets down to them, which adds tets and,
  // where the stress is singular (a fixed joint's edge, a junction), raises the peak. Those edges are
  // collapsed, the shortest first, up to half the edge length.
  Soup s = surfaceOf(cage, kFiniteFaces);
  int keptNearCrossings = 0;
  const int collapsed = collapseShortEdges(s, kShortEdge * opt.edgeLength, &keptNearCrossings);
  if (collapsed > 0) toMesh(s, cage);
  relabel(cage, joinedSurface);
  const std::string shortEdges = "edges under " + mm(kShortEdge * opt.edgeLength, 1) + " mm";
  log.push_back("decimated to edge length " + mm(opt.edgeLength, 2) + " mm: " + std::to_string(cage.fn) + " faces" +
                (collapsed > 0  ? ", " + std::to_string(collapsed) + " " + shortEdges + " collapsed" +
                                     (keptNearCrossings > 0 ? " (" + std::to_string(keptNearCrossings) +
                                                                  " edges kept where collapsing made the surface cross itself)"
                                                            : std::string())
                 : collapsed < 0 ? ", " + shortEdges + " kept (collapsing them made the surface cross itself)"
                                 : std::string()));
}

void Preparation::placeAndCentre(CMeshO& cage) {
  prog(90, "landmarks");
  // the full-detail union without the column (see join()): the landmarks depend neither on the edge length nor
  // on the spine mode
  Anatomy an = anatomyOf(joined);
  an.spine = spine;
  std::set<int> given;
  for (const auto& u : opt.userLandmarks) given.insert(u.code);
  auto lms = placeLandmarks(an, x0, yMid, given, log);
  double ySpine = 0, zLow = 1e300;
  std::map<int, double> zBySide[3];
  {
    bool spineAt = false;
    for (const auto& l : lms)
      if (l.code == kVertebraAtDeepest) ySpine = l.p.y(), spineAt = true;
    double yc = 0;
    int n = 0;
    for (const auto& l : lms)
      if (l.code > 100 && l.code < 213) yc += l.p.y(), ++n, zLow = std::min(zLow, l.p.z()), zBySide[l.code / 100][l.code % 100] = l.p.z();
    if (!spineAt) ySpine = n ? yc / n : 0;
  }
  double spacing = 0;
  int ns = 0;
  for (int side = 1; side <= 2; ++side)
    for (const auto& [rib, z] : zBySide[side])
      if (auto it = zBySide[side].find(rib + 1); it != zBySide[side].end()) spacing += z - it->second, ++ns;
  spacing = ns ? spacing / ns : 0;
  const Vec3 shift(-x0, -ySpine, -(zLow - 0.5 * spacing));
  for (auto& v : cage.vert) v.P() += toPoint(shift);
  for (auto& l : lms) l.p += shift;
  vcg::tri::UpdateBounding<CMeshO>::Box(cage);
  res.inputToModel.setIdentity();
  res.inputToModel.topLeftCorner<3, 3>() = scale * fr.R;
  res.inputToModel.topRightCorner<3, 1>() = shift;
  // user points override
  for (const auto& u : opt.userLandmarks) {
    const Vec3 p = (res.inputToModel * u.p.homogeneous()).head<3>();
    auto it = std::find_if(lms.begin(), lms.end(), [&](const Landmark& l) { return l.code == u.code; });
    log.push_back("landmark " + std::to_string(u.code) + ": the user's point " + at(p) +
                  (it != lms.end() ? " replaces the automatic " + at(it->p) : std::string(" (no automatic one)")));
    if (it != lms.end()) it->p = p;
    else lms.push_back({u.code, p});
  }
  std::sort(lms.begin(), lms.end(), [](const Landmark& a, const Landmark& b) { return a.code < b.code; });
  res.landmarks = lms;
}

}  // namespace

NameClass classifyName(const std::string& name) {
  const auto w = words(name);
  auto has = [&](const char* prefix) {
    return std::any_of(w.begin(), w.end(), [&](const std::string& x) { return x.rfind(prefix, 0) == 0; });
  };
  NameClass c;
  for (const auto& x : w) {
    if (x == "left" || x == "l" || x == "lt" || x == "sinister") c.side = 2;
    if (x == "right" || x == "r" || x == "rt" || x == "dexter") c.side = 1;
  }
  for (const auto& x : w)
    if (std::isdigit(static_cast<unsigned char>(x[0])) && x.size() <= 2) c.number = std::stoi(x);
  static const char* notCage[] = {"scapul", "clavic", "humer", "femur", "hip", "skull", "lung", "heart", "liver",
                                  "aorta", "trachea", "esophag", "kidney", "spleen", "stomach", "sacrum", "pelvi",
                                  "skin", "body", "muscle", "fat", "vein", "arter", "atrial", "ventric", "thyroid", "cord",
                                  // the rest of TotalSegmentator's classes: organs, vessels, muscles (never a candidate
                                  // sternum or cartilage by their shape when a label map holds them)
                                  "pancrea", "colon", "bowel", "duoden", "gallbladder", "bladder", "prostat", "adrenal",
                                  "cyst", "gland", "glute", "autochthon", "iliopsoas", "psoas", "brain", "portal",
                                  "vena", "cava", "trunk", "carotid", "subclavian", "appendage", "pulmonar", "iliac",
                                  "intestin", "rectum", "uterus", "spleen"};
  for (const char* n : notCage)
    if (has(n)) return {Kind::NotCage, c.side, c.number};
  if (has("cartilag") || has("chondr")) return {Kind::Cartilage, c.side, c.number};
  if (has("stern") || has("manubr") || has("xiph")) return {Kind::Sternum, 0, 0};
  if (has("vertebr") || has("spine") || has("spinal") || has("column")) return {Kind::Vertebra, 0, 0};
  const bool rib = has("rib") || has("costa");
  if (rib && c.number >= 1 && c.number <= 12) return {Kind::Rib, c.side, c.number};
  if (rib || has("bone") || has("skelet") || has("thorax") || has("cage")) return {Kind::Bone, c.side, 0};
  return {Kind::Unknown, c.side, c.number};
}

std::vector<Landmark> readPickedPoints(const std::string& path, int* skipped) {
  std::ifstream in(path);
  if (!in) throw IOError("Cannot read the picked points file '" + path + "': check the path.");
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  std::vector<Landmark> out;
  int skip = 0;
  const std::regex point("<point\\b([^>]*)/?>");
  auto attr = [](const std::string& tag, const std::string& key, std::string& val) {
    const std::regex r("\\b" + key + "\\s*=\\s*\"([^\"]*)\"");
    std::smatch m;
    if (!std::regex_search(tag, m, r)) return false;
    val = m[1];
    return true;
  };
  for (auto it = std::sregex_iterator(text.begin(), text.end(), point); it != std::sregex_iterator(); ++it) {
    const std::string tag = (*it)[1];
    std::string x, y, z, name, active = "1";
    attr(tag, "active", active);
    if (!attr(tag, "x", x) || !attr(tag, "y", y) || !attr(tag, "z", z) || !attr(tag, "name", name) || active == "0") {
      ++skip;
      continue;
    }
    std::size_t k = 0;
    while (k < name.size() && std::isspace(static_cast<unsigned char>(name[k]))) ++k;
    std::size_t e = k;
    while (e < name.size() && std::isdigit(static_cast<unsigned char>(name[e]))) ++e;
    if (e == k) {
      ++skip;
      continue;
    }
    out.push_back({std::stoi(name.substr(k, e - k)), Vec3(std::stod(x), std::stod(y), std::stod(z))});
  }
  if (out.empty() && text.find("<PickedPoints") == std::string::npos)
    throw IOError("'" + path + "' is not a PickPoints file (.pp): no <PickedPoints> element.");
  if (skipped) *skipped = skip;
  return out;
}

PrepareResult preparePatientCage(const std::vector<InputLayer>& layers, const PrepareOptions& opt, CMeshO& cage,
                                 const std::function<void(int, const char*)>& progress) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  auto t = t0;
  std::string times;
  const auto lap = [&](const char* step) {
    const auto now = Clock::now();
    times += (times.empty() ? "" : ", ") + std::string(step) + " " + mm(std::chrono::duration<double>(now - t).count()) + " s";
    t = now;
  };
  Preparation p(opt, progress);
  try {
    p.classify(layers);
    p.toMillimetres();
    p.orient();
    lap("classify, units and frame");
    p.separate();
    lap("solids and separate");
    p.settleSuperiorAndLeft();
    p.numberRibs();
    lap("number");
    p.join(cage);
    lap("join and decimate");
    p.placeAndCentre(cage);
  } catch (const InputError& e) {
    throw PrepareRefusal(e.what(), p.res.log);
  }
  lap("landmarks");
  p.res.log.push_back("time: " + times);
  p.res.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  if (progress) progress(100, "done");
  return p.res;
}

}  // namespace pectus::patient
