#include "pectus/patient/shape_classify.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "pectus/errors.h"
#include "pectus/format.h"

namespace pectus::patient {

namespace {
using Vec3 = Eigen::Vector3d;

// Thresholds, as fractions of the whole's bounding-box diagonal D unless noted. Measured on the CT phantom's
// 1 mm export of a 7-year-old (D = 364 mm): ribs 0.21-0.32 D long, sheet 0.26-0.43; cartilage pieces 0.03-0.30 D
// (median 0.13), thinness 0.03-0.15; the sternum 0.32 D, 2.4 times as long as wide, 0.10 D from the
// cartilages' centre (the nearest rib 0.25 D); vertebrae 0.08 D, as wide as long, thinness 0.22; scapulae
// sheet 0.71, 0.20 D beside the midline.
constexpr double kSignificant = 0.05;     // a piece counts if it holds 5 % of the layer's largest piece's volume
constexpr double kLongPiece = 0.22;       // median piece length: ribs above, cartilage pieces below
constexpr double kBarThinness = 0.12;     // 2 V / (A L) of a bar (cartilage, rib) below, of a block above
constexpr double kBlock = 0.15;           // thickness 2 V / A over width: vertebrae (0.24) above, ribs (0.06) below
constexpr double kFusedLength = 0.5;      // one piece this long and kFusedWidth wide: ribs fused to the spine
constexpr double kFusedWidth = 0.3;
constexpr double kElongated = 1.6;        // length / width of an elongated piece
constexpr double kSternumReach = 0.25;    // the sternum lies this near the cartilages' centre at most
constexpr double kSternumMargin = 1.5;    // the next candidate must lie this many times as far
constexpr double kMidline = 0.06;         // |lateral offset| of midline structures
constexpr double kLateral = 0.12;         // lateral offset of a scapula at least
constexpr double kPlate = 0.55;           // sheet = area / (2 length width): plates above, bars below
constexpr double kMinRib = 0.12;          // a rib is at least this long

std::string num(double v) { return significantText(v, 3); }

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
  return v[v.size() / 2];
}

struct Extents {
  Vec3 axis = Vec3::UnitX();  // the principal direction
  double l[3] = {0, 0, 0};     // extents along the principal axes, longest first
};
Extents extentsOf(const std::vector<Vec3>& pts) {
  Extents e;
  if (pts.size() < 2) return e;
  Vec3 m = Vec3::Zero();
  for (const auto& p : pts) m += p;
  m /= double(pts.size());
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (const auto& p : pts) C += (p - m) * (p - m).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(C);
  for (int k = 0; k < 3; ++k) {
    const Vec3 d = eig.eigenvectors().col(2 - k);
    double lo = 1e300, hi = -1e300;
    for (const auto& p : pts) lo = std::min(lo, p.dot(d)), hi = std::max(hi, p.dot(d));
    e.l[k] = hi - lo;
  }
  e.axis = eig.eigenvectors().col(2);
  return e;
}

// A layer's shape from its significant pieces (specks and stray voxels do not count)
struct Shape {
  int pieces = 0;
  double volume = 0, area = 0;
  Vec3 centre = Vec3::Zero();  // area-weighted
  Extents ext;
  double pieceLength = 0;      // median length of the pieces
  double pieceThinness = 0;    // median 2 V / (A L) of the pieces: a bar small, a block large
  std::vector<Vec3> points;    // the significant pieces' vertices
  double length() const { return ext.l[0]; }
  double width() const { return ext.l[1]; }
  double thickness() const { return 2 * volume / std::max(area, 1e-300); }
  double sheet() const { return area / std::max(2 * ext.l[0] * ext.l[1], 1e-300); }  // plate ~0.7, bar ~0.3
  bool elongated() const { return ext.l[0] >= kElongated * ext.l[1]; }
  std::string size() const { return num(ext.l[0]) + " x " + num(ext.l[1]) + " x " + num(ext.l[2]); }
};

Shape shapeOf(const Soup& s) {
  Shape sh;
  auto pieces = components(s);
  std::vector<double> vol;
  for (const auto& p : pieces) vol.push_back(volume(p));
  const double big = vol.empty() ? 0 : *std::max_element(vol.begin(), vol.end());
  Soup sig;
  std::vector<double> lengths, thinness;
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    if (vol[i] < kSignificant * big) continue;
    const double a = area(pieces[i]), l = extentsOf(pieces[i].V).l[0];
    append(sig, pieces[i]);
    sh.volume += vol[i], sh.area += a;
    lengths.push_back(l);
    thinness.push_back(2 * vol[i] / std::max(a * l, 1e-300));
  }
  sh.pieces = int(lengths.size());
  sh.centre = centroid(sig);
  sh.ext = extentsOf(sig.V);
  sh.pieceLength = median(lengths);
  sh.pieceThinness = median(thinness);
  sh.points = std::move(sig.V);
  return sh;
}

class ShapeClassifier {
 public:
  ShapeClassifier(const std::vector<LayerToClassify>& layers, std::vector<std::string>& log) : in(layers), log(log) {
    for (const auto& l : layers) cls.push_back(l.cls), shape.push_back(shapeOf(*l.soup));
    Eigen::AlignedBox3d box;
    double a = 0;
    for (const auto& s : shape) {
      for (const auto& p : s.points) box.extend(p);
      G += s.area * s.centre, a += s.area;
    }
    D = box.isEmpty() ? 0 : box.diagonal().norm();
    G /= std::max(a, 1e-300);
  }
  std::vector<NameClass> run() {
    boneAndCartilage();
    const Vec3 cart = cartilageCentre();
    const int st = sternum(cart);
    axesFrom(st);
    theRest();
    return cls;
  }

 private:
  bool open(std::size_t i) const { return cls[i].kind == Kind::Unknown && shape[i].pieces > 0; }
  void decide(std::size_t i, Kind k, const std::string& why) {
    cls[i].kind = k;
    static const char* names[] = {"rib", "costal cartilage", "sternum", "vertebra", "bone",
                                  "not rib cage", "unknown"};
    log.push_back("'" + in[i].name + "': " + names[int(k)] + " (by its shape: " + why + ")");
  }
  [[noreturn]] void refuse(const std::string& why) const {
    std::string unnamed;
    int n = 0;
    for (const auto& l : in)
      if (l.cls.kind == Kind::Unknown && ++n <= 6) unnamed += (unnamed.empty() ? "'" : ", '") + l.name + "'";
    if (n > 6) unnamed += ", ... (" + std::to_string(n) + " layers)";
    throw InputError("Cannot tell the rib cage's structures from the shapes of the layers whose names say nothing (" +
                     unnamed + "): " + why + ". Rename the layers: 'sternum', 'costal_cartilages', the ribs "
                     "'rib_left_1' ... 'rib_right_12' (or one layer 'ribs' or 'bone'), the spine 'vertebrae_T1' ...");
  }

  // many long pieces, or the largest layer in a few pieces as wide as the cage: bone; many small bars: the
  // costal cartilages
  void boneAndCartilage() {
    double largest = 0;  // ribs fused to the spine outweigh every other structure
    for (const auto& s : shape) largest = std::max(largest, s.volume);
    for (std::size_t i = 0; i < in.size(); ++i) {
      if (!open(i)) continue;
      const Shape& s = shape[i];
      if (s.pieces >= 4 && s.pieceLength >= kLongPiece * D)
        decide(i, Kind::Bone, std::to_string(s.pieces) + " long pieces, median length " + num(s.pieceLength) + ", the whole's diagonal " +
                                  num(D) + ": ribs, maybe fused to the spine");
      else if (s.pieces < 4 && s.length() >= kFusedLength * D && s.width() >= kFusedWidth * D && s.volume >= largest)
        decide(i, Kind::Bone, "the largest layer, " + s.size() + ", the whole's diagonal " + num(D) + ": ribs fused to the spine");
      else if (s.pieces >= 4 && s.pieceThinness < kBarThinness)
        decide(i, Kind::Cartilage, std::to_string(s.pieces) + " small bar-like pieces, median length " + num(s.pieceLength) +
                                       ", the whole's diagonal " + num(D));
    }
  }

  Vec3 cartilageCentre() const {
    Vec3 c = Vec3::Zero();
    double a = 0;
    for (std::size_t i = 0; i < in.size(); ++i)
      if (cls[i].kind == Kind::Cartilage) c += shape[i].area * shape[i].centre, a += shape[i].area;
    if (a <= 0) refuse("no layer holds many small bar-like pieces, as the costal cartilages do");
    return c / a;
  }

  // the named sternum, else the elongated one-piece layer nearest the cartilages' centre
  int sternum(const Vec3& cart) {
    for (std::size_t i = 0; i < in.size(); ++i)
      if (cls[i].kind == Kind::Sternum) return int(i);
    std::vector<std::pair<double, std::size_t>> cand;
    for (std::size_t i = 0; i < in.size(); ++i)
      if (open(i) && shape[i].pieces <= 2 && shape[i].elongated()) cand.push_back({(shape[i].centre - cart).norm(), i});
    std::sort(cand.begin(), cand.end());
    if (cand.empty() || cand[0].first > kSternumReach * D)
      refuse("no elongated one-piece layer lies near the cartilages' centre, as the sternum does" +
             (cand.empty() ? std::string() : " (the nearest, '" + in[cand[0].second].name + "', " + num(cand[0].first) + " away)"));
    const auto [d0, i0] = cand[0];
    if (cand.size() > 1 && cand[1].first < kSternumMargin * d0)
      refuse("'" + in[i0].name + "' and '" + in[cand[1].second].name + "' are equally good sternums (" + num(d0) + " and " +
             num(cand[1].first) + " from the cartilages' centre)");
    decide(i0, Kind::Sternum, "one piece " + shape[i0].size() + ", the elongated piece nearest the cartilages, " + num(d0) +
                                  " from their centre" +
                                  (cand.size() > 1 ? "; the next, '" + in[cand[1].second].name + "', " + num(cand[1].first) : std::string()));
    return int(i0);
  }

  // provisional axes: long along the sternum, anterior from the whole's centre to the sternum square to the
  // long axis (the sternum lies higher or lower than the whole's centre), lateral square to both
  void axesFrom(int st) {
    const Shape& s = shape[std::size_t(st)];
    lon = s.ext.axis.normalized();
    ant = (s.centre - G) - (s.centre - G).dot(lon) * lon;
    if (ant.norm() < 1e-9 * std::max(D, 1e-300)) ant = lon.unitOrthogonal();
    ant.normalize();
    lat = lon.cross(ant);
  }

  void theRest() {
    for (std::size_t i = 0; i < in.size(); ++i) {
      if (!open(i)) {
        if (cls[i].kind == Kind::Unknown)
          log.push_back("'" + in[i].name + "': no piece with a volume, left out");
        continue;
      }
      const Shape& s = shape[i];
      const Vec3 r = s.centre - G;
      const double side = std::abs(r.dot(lat)) / D, front = r.dot(ant) / D;
      double back = 1e300, ahead = -1e300;  // the layer's extent along the anterior axis, from the whole's centre
      for (const auto& p : s.points) back = std::min(back, (p - G).dot(ant) / D), ahead = std::max(ahead, (p - G).dot(ant) / D);
      const std::string where = num(side * D) + " beside the midline, " + num(std::abs(front) * D) +
                                (front >= 0 ? " in front of" : " behind") + " the whole's centre";
      const bool alongSpine = std::abs(s.ext.axis.dot(lon)) > std::cos(30.0 * M_PI / 180.0);
      if (front < 0 && side < kMidline && (!s.elongated() || alongSpine) && s.thickness() >= kBlock * s.width())
        decide(i, Kind::Vertebra, (s.pieces > 1 ? std::to_string(s.pieces) + " compact blocks " : "a compact block ") + s.size() +
                                      ", " + where);
      else if (front < 0 && side >= kLateral && s.sheet() >= kPlate)
        decide(i, Kind::NotCage, "a plate " + s.size() + ", " + where + ": a scapula, left out");
      else if (side >= kMidline && s.pieces <= 2 && s.elongated() && s.sheet() < kPlate && s.length() >= kMinRib * D && back < 0)
        decide(i, Kind::Rib, "a thin elongated piece " + s.size() + ", " + where + ", reaching " + num(-back * D) + " behind it");
      else if (back > 0 && s.pieceThinness < kBarThinness && s.length() < kLongPiece * D)
        decide(i, Kind::Cartilage, "small bar-like pieces " + s.size() + " wholly in front of the whole's centre");
      else
        log.push_back("'" + in[i].name + "': left out: its shape (" + std::to_string(s.pieces) + " piece" + (s.pieces > 1 ? "s " : " ") +
                      s.size() + ", " + where + ") is none of the rib cage's structures; rename it to include it");
    }
  }

  const std::vector<LayerToClassify>& in;
  std::vector<std::string>& log;
  std::vector<NameClass> cls;
  std::vector<Shape> shape;
  double D = 0;
  Vec3 G = Vec3::Zero();           // the whole's area-weighted centre
  Vec3 ant = Vec3::UnitY(), lon = Vec3::UnitZ(), lat = Vec3::UnitX();
};

}  // namespace

std::vector<NameClass> classifyByShape(const std::vector<LayerToClassify>& layers, std::vector<std::string>& log) {
  return ShapeClassifier(layers, log).run();
}

}  // namespace pectus::patient
