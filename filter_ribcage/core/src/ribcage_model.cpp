#include "pectus/ribcage/ribcage_model.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pectus::ribcage {

namespace {
using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;

double smoothstep(double t) {
  t = std::clamp(t, 0.0, 1.0);
  return t * t * (3 - 2 * t);
}
double bump(double t) {  // compact support [-1, 1], 1 at 0, C1
  if (std::abs(t) >= 1) return 0;
  const double s = 1 - t * t;
  return s * s;
}

// centripetal Catmull-Rom through pts, densely sampled
std::vector<Vec2> catmullRom(const std::vector<Vec2>& P, int perSeg = 64) {
  const int n = int(P.size());
  std::vector<Vec2> Q;
  Q.reserve(std::size_t(n + 2));
  Q.push_back(2 * P[0] - P[1]);
  for (const auto& p : P) Q.push_back(p);
  Q.push_back(2 * P[n - 1] - P[n - 2]);
  std::vector<Vec2> out;
  for (int i = 1; i + 2 < int(Q.size()); ++i) {
    const Vec2 &p0 = Q[i - 1], &p1 = Q[i], &p2 = Q[i + 1], &p3 = Q[i + 2];
    const double t0 = 0, t1 = t0 + std::sqrt((p1 - p0).norm()), t2 = t1 + std::sqrt((p2 - p1).norm()),
                 t3 = t2 + std::sqrt((p3 - p2).norm());
    for (int k = 0; k < perSeg; ++k) {
      const double t = t1 + (t2 - t1) * k / perSeg;
      const Vec2 a1 = (t1 - t) / (t1 - t0) * p0 + (t - t0) / (t1 - t0) * p1;
      const Vec2 a2 = (t2 - t) / (t2 - t1) * p1 + (t - t1) / (t2 - t1) * p2;
      const Vec2 a3 = (t3 - t) / (t3 - t2) * p2 + (t - t2) / (t3 - t2) * p3;
      const Vec2 b1 = (t2 - t) / (t2 - t0) * a1 + (t - t0) / (t2 - t0) * a2;
      const Vec2 b2 = (t3 - t) / (t3 - t1) * a2 + (t - t1) / (t3 - t1) * a3;
      out.push_back((t2 - t) / (t2 - t1) * b1 + (t - t1) / (t2 - t1) * b2);
    }
  }
  out.push_back(P.back());
  return out;
}

// resample a dense 2D polyline by arc length: returns points and u in [0,1]
void resample(const std::vector<Vec2>& dense, double spacing, std::vector<Vec2>& pts, std::vector<double>& u) {
  std::vector<double> s(dense.size(), 0.0);
  for (std::size_t i = 1; i < dense.size(); ++i) s[i] = s[i - 1] + (dense[i] - dense[i - 1]).norm();
  const double L = s.back();
  const int n = std::max(8, int(std::ceil(L / spacing)));
  pts.clear();
  u.clear();
  std::size_t j = 0;
  for (int k = 0; k <= n; ++k) {
    const double t = L * k / n;
    while (j + 2 < dense.size() && s[j + 1] < t) ++j;
    const double w = s[j + 1] > s[j] ? std::clamp((t - s[j]) / (s[j + 1] - s[j]), 0.0, 1.0) : 0.0;
    pts.push_back((1 - w) * dense[j] + w * dense[j + 1]);
    u.push_back(double(k) / n);
  }
}

// frames: t tangent, n = major axis (as close to +z as possible, or +x for the sternum), b = t x n
void frames(Curve& c, const Vec3& up) {
  const std::size_t n = c.c.size();
  c.n.resize(n);
  c.b.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 t = (c.c[std::min(i + 1, n - 1)] - c.c[i == 0 ? 0 : i - 1]).normalized();
    Vec3 nn = up - up.dot(t) * t;
    if (nn.norm() < 0.2) nn = Vec3::UnitX() - Vec3::UnitX().dot(t) * t;
    nn.normalize();
    c.n[i] = nn;
    c.b[i] = t.cross(nn);
  }
}

double lerpTable(const std::vector<std::pair<double, double>>& tab, double z) {  // tab: z descending
  if (z >= tab.front().first) return tab.front().second;
  for (std::size_t i = 1; i < tab.size(); ++i)
    if (z >= tab[i].first) {
      const double w = (tab[i - 1].first - z) / (tab[i - 1].first - tab[i].first);
      return (1 - w) * tab[i - 1].second + w * tab[i].second;
    }
  return tab.back().second;
}
}  // namespace

double CageModel::funnel(double x, double y, double z) const {
  const double fzAbs = zNotch - fz * (zNotch - zXJ);
  const double aw = smoothstep((y - 0.35 * d.chestDepth) / (0.35 * d.chestDepth));
  return bump((x - fx) / (0.5 * fw)) * bump((z - fzAbs) / (0.5 * fh)) * aw;
}

std::array<double, 2> cartilageDiameters(const Dimensions& d, CartilageSection s) {
  if (s == CartilageSection::Ct) {
    const double diameter = std::sqrt(2 * d.ribHeight * d.ribThickness);  // pi (D/2)^2 = 2 pi (h/2) (t/2)
    return {diameter, diameter};
  }
  return {0.85 * d.ribHeight, 1.05 * d.ribThickness};
}

double autoBlend(const Dimensions& d) { return std::clamp(0.45 * d.ribThickness, 1.2, 3.0); }

namespace {
// rib k's centre-line half width as a fraction of the widest rib's (index: rib 1-12)
constexpr double kRibWidth[13] = {0, 0.56, 0.70, 0.80, 0.88, 0.94, 0.98, 1.0, 0.99, 0.96, 0.92, 0.86, 0.76};

// the model's parameters and its heights: vertebral level spacing, sternal notch, manubriosternal and
// xiphisternal joints, xiphoid tip
CageModel modelLevels(const Dimensions& d, const RibCageParams& p, double funnelDepth, double spacing) {
  CageModel m;
  m.d = d;
  m.ribPairs = p.ribPairs;
  m.funnelDepth = funnelDepth;
  m.fx = p.funnelCenterX;
  m.fz = p.funnelCenterZ;
  m.fw = p.funnelWidth;
  m.fh = p.funnelHeight;
  m.spacing = spacing;
  m.blend = p.blend < 0 ? autoBlend(d) : p.blend;
  m.cartilageSection = p.cartilageSection;
  const double L = d.spineHeight;
  const double dl = L / 12.0;
  m.delta = dl;
  m.zNotch = L - 2.3 * dl;
  m.zXJ = L - 8.8 * dl;
  m.zMS = m.zNotch - 0.27 * (m.zNotch - m.zXJ);
  m.zTip = m.zXJ - 0.9 * dl;
  return m;
}

// sternum cross-section along z (descending tables), rest centre line and funnel displacement
struct SternumProfile {
  const CageModel& m;
  std::vector<std::pair<double, double>> width, thick;
  double fzAbs;  // the funnel centre's height

  explicit SternumProfile(const CageModel& model) : m(model) {
    const double ws = m.d.sternumWidth, ts = m.d.sternumThickness;
    width = {{m.zNotch, 1.35 * ws}, {m.zMS, 1.0 * ws}, {m.zXJ + 4, 1.05 * ws}, {m.zXJ - 3, 0.55 * ws}, {m.zTip, 0.3 * ws}};
    thick = {{m.zNotch, 1.15 * ts}, {m.zMS, 1.0 * ts}, {m.zXJ + 4, 1.0 * ts}, {m.zXJ - 3, 0.6 * ts}, {m.zTip, 0.45 * ts}};
    fzAbs = m.zNotch - m.fz * (m.zNotch - m.zXJ);
  }
  double posterior(double z) const {
    const double phi = std::clamp((m.zNotch - z) / (m.zNotch - m.zXJ), 0.0, 1.3);
    return m.d.chestDepth * (1 + 0.12 * phi);
  }
  double centreY(double z) const { return posterior(z) + 0.5 * lerpTable(thick, z); }
  double dy(double z) const {
    return -m.funnelDepth * bump((0 - m.fx) / (0.5 * m.fw)) * bump((z - fzAbs) / (0.5 * m.fh));
  }
};

// rib k attachment heights on the sternum (ribs 1-7)
double zAttach(const CageModel& m, int k) {
  if (k == 1) return m.zNotch - 0.45 * (m.zNotch - m.zMS);
  if (k == 2) return m.zMS;
  return m.zMS + (k - 2) / 5.0 * (m.zXJ - m.zMS);
}

// a rib's rest state: centre line, its u, the funnel's displacement along y, and where the cartilage starts
struct RibRest {
  std::vector<Vec3> c;
  std::vector<double> u, dy;
  double ucc = 2;
};

// control points (|x|, y) of rib k, half width a, from the spine round to the front: ribs 1-7 end on the
// sternum, 8-10 on the cartilage of the rib above (parent; parentSample: its sample they join), 11 and 12
// end free. zEnd: the front end's height (ribs 1-10)
std::vector<Vec2> ribOutline(const CageModel& m, const SternumProfile& st, int k, double a, const RibRest& parent,
                             double& zEnd, int& parentSample) {
  const double T = m.d.chestWidth, D0 = m.d.chestDepth;
  std::vector<Vec2> P = {{0.075 * T, -0.20 * D0}, {0.30 * a, -0.45 * D0}, {0.75 * a, -0.28 * D0}, {a, 0.22 * D0}};
  zEnd = 0;
  parentSample = -1;
  const double xs = 0.30 * m.d.sternumWidth;
  if (k <= 7) {
    const double ye = st.centreY(zAttach(m, k));
    P.push_back({0.86 * a, 0.66 * D0});
    P.push_back({xs + 0.40 * (a - xs), ye - 0.10 * D0});
    P.push_back({xs, ye});
    zEnd = zAttach(m, k);
  } else if (k <= 10) {
    const double uj = parent.ucc + 0.5 * (1 - parent.ucc);
    parentSample = int(std::lower_bound(parent.u.begin(), parent.u.end(), uj) - parent.u.begin());
    const Vec3 J = parent.c[std::size_t(parentSample)];
    P.push_back({0.86 * a, 0.66 * D0});
    P.push_back({std::abs(J.x()), J.y()});
    zEnd = J.z();
  } else if (k == 11) {
    P.push_back({0.92 * a, 0.45 * D0});
  } else {
    P.back() = {0.97 * a, 0.05 * D0};
  }
  return P;
}

// the rest centre line's height: from zk at the spine down by `drop` at the cartilage start, then on to
// zEnd at the front; the floating ribs (11, 12) follow rib 10's slope by arc length (refLen: rib 10's
// arc length to its costochondral junction)
void restHeights(RibRest& r, const std::vector<Vec2>& pts, int k, double sg, double zk, double drop, double zEnd,
                 double len, double refLen, double dl) {
  const std::vector<double>& u = r.u;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    double z;
    if (k > 10) z = zk - dl * 4.25 * smoothstep(u[i] * len / (refLen * kRibWidth[k] / kRibWidth[10]));
    else if (u[i] <= r.ucc) z = zk - drop * smoothstep(u[i] / r.ucc);
    else z = (zk - drop) + (zEnd - (zk - drop)) * smoothstep((u[i] - r.ucc) / (1 - r.ucc));
    r.c.push_back(Vec3(sg * pts[i].x(), pts[i].y(), z));
  }
}

// funnel displacement, blended at the sternal / parental end over the last 12 mm so that ribs 1-10 follow
// what they join
void funnelDisplacement(RibRest& r, const CageModel& m, const SternumProfile& st, int k, double len,
                        const RibRest& parent, int parentSample) {
  const double ub = std::min(0.5, 12.0 / std::max(len, 1.0));
  r.dy.resize(r.c.size());
  for (std::size_t i = 0; i < r.c.size(); ++i) {
    const Vec3& c = r.c[i];
    double dy = -m.funnelDepth * m.funnel(c.x(), c.y(), c.z());
    if (k <= 10) {
      const double target = k <= 7 ? st.dy(c.z()) : parent.dy[std::size_t(parentSample)];
      const double w = smoothstep((r.u[i] - (1 - ub)) / ub);
      dy = (1 - w) * dy + w * target;
    }
    r.dy[i] = dy;
  }
}

// the rib's curve: displaced centre line, cross-section radii (bone, growing to the lateral point uLat,
// then cartilage), frames
Curve ribCurve(const CageModel& m, const RibRest& r, int k, int side, double uLat) {
  const double hr = m.d.ribHeight, tr = m.d.ribThickness;
  const std::array<double, 2> cartilage = cartilageDiameters(m.d, m.cartilageSection);
  Curve cv;
  cv.side = side;
  cv.rib = k;
  cv.uCartilage = r.ucc;
  cv.u = r.u;
  for (std::size_t i = 0; i < r.c.size(); ++i) {
    cv.c.push_back(r.c[i] + Vec3(0, r.dy[i], 0));
    const double ui = r.u[i];
    const double bone = std::clamp(ui / std::max(uLat, 1e-3), 0.0, 1.0);
    const double raB = 0.5 * hr * (0.78 + 0.22 * smoothstep(bone)), rbB = 0.5 * tr;
    const double raC = 0.5 * cartilage[0], rbC = 0.5 * cartilage[1];
    const double w = smoothstep((ui - (r.ucc - 0.03)) / 0.06);
    cv.ra.push_back((1 - w) * raB + w * raC);
    cv.rb.push_back((1 - w) * rbB + w * rbC);
  }
  frames(cv, Vec3::UnitZ());
  return cv;
}

// rib k of side si (0: right, 1: left): its rest state rest[k][si] (ribs 8-10 join rest[k - 1][si]) and
// its curve; refLen[si]: rib 10's arc length to its costochondral junction (set at rib 10)
Curve buildRib(const CageModel& m, const SternumProfile& st, int k, int si, std::vector<std::array<RibRest, 2>>& rest,
               double refLen[2]) {
  const int side = si + 1;
  const double sg = side == 1 ? -1.0 : 1.0;  // side 1 = right = -x
  const double A = 0.5 * m.d.chestWidth + 0.5 * m.d.ribThickness;  // centre line of the widest rib: inner surface at T/2
  const double a = A * kRibWidth[k];
  const double dl = m.delta;
  const double zk = m.d.spineHeight - (k - 0.5) * dl;
  const RibRest& parent = rest[std::size_t(k - 1)][std::size_t(si)];
  double zEnd = 0;
  int parentSample = -1;
  const std::vector<Vec2> P = ribOutline(m, st, k, a, parent, zEnd, parentSample);
  std::vector<Vec2> pts;
  std::vector<double> u;
  resample(catmullRom(P), m.spacing, pts, u);
  // lateral point and cartilage start
  std::size_t iLat = 0;
  for (std::size_t i = 0; i < pts.size(); ++i)
    if (pts[i].x() > pts[iLat].x()) iLat = i;
  const double uLat = u[iLat];
  RibRest& r = rest[std::size_t(k)][std::size_t(si)];
  const double ck = 0.46 + 0.015 * (k - 1);
  r.ucc = k <= 10 ? uLat + (1 - ck) * (1 - uLat) : 0.88;
  const double drop = k <= 10 ? dl * (2.0 + 0.25 * (k - 1)) : (k == 11 ? 2.0 * dl : 1.5 * dl);
  r.u = u;
  const double len = double(pts.size() - 1) * m.spacing;
  if (k == 10) refLen[si] = len * r.ucc;
  restHeights(r, pts, k, sg, zk, drop, zEnd, len, refLen[si], dl);
  funnelDisplacement(r, m, st, k, len, parent, parentSample);
  return ribCurve(m, r, k, side, uLat);
}

// the sternum's curve (the model's last), from the notch to the xiphoid tip
Curve sternumCurve(const CageModel& m, const SternumProfile& sp) {
  Curve st;
  const double len = m.zNotch - m.zTip;
  const int n = std::max(8, int(std::ceil(len / m.spacing)));
  for (int i = 0; i <= n; ++i) {
    const double z = m.zNotch - len * i / n;
    st.c.push_back(Vec3(0, sp.centreY(z) + sp.dy(z), z));
    st.u.push_back(double(i) / n);
    st.ra.push_back(0.5 * lerpTable(sp.width, z));
    st.rb.push_back(0.5 * lerpTable(sp.thick, z));
  }
  st.sternumSplit = {(m.zNotch - m.zMS) / len, (m.zNotch - m.zXJ) / len, 1.0};
  frames(st, Vec3::UnitX());
  return st;
}
}  // namespace

CageModel buildModel(const Dimensions& d, const RibCageParams& p, double funnelDepth, double spacing) {
  CageModel m = modelLevels(d, p, funnelDepth, spacing);
  const SternumProfile sternum(m);
  std::vector<std::array<RibRest, 2>> rest(std::size_t(p.ribPairs + 1));
  double refLen[2] = {0, 0};
  for (int k = 1; k <= p.ribPairs; ++k)
    for (int si = 0; si < 2; ++si) m.curves.push_back(buildRib(m, sternum, k, si, rest, refLen));
  m.curves.push_back(sternumCurve(m, sternum));
  return m;
}

// ------------------------------------------------------------------------------------------------

CageField::CageField(const CageModel& m, double cell, const std::function<bool(const Curve&, int)>& keep) : m_(m), cell_(cell) {
  lo_ = Vec3::Constant(std::numeric_limits<double>::max());
  hi_ = -lo_;
  for (int ci = 0; ci < int(m.curves.size()); ++ci) {
    const Curve& c = m.curves[std::size_t(ci)];
    for (int i = 0; i + 1 < int(c.c.size()); ++i) {
      if (keep && !keep(c, i)) continue;
      const double r = std::max({c.ra[std::size_t(i)], c.rb[std::size_t(i)], c.ra[std::size_t(i + 1)],
                                 c.rb[std::size_t(i + 1)]}) + m.blend + 1.0;
      Seg s{ci, i, c.c[std::size_t(i)].cwiseMin(c.c[std::size_t(i + 1)]) - Vec3::Constant(r),
            c.c[std::size_t(i)].cwiseMax(c.c[std::size_t(i + 1)]) + Vec3::Constant(r)};
      lo_ = lo_.cwiseMin(s.lo);
      hi_ = hi_.cwiseMax(s.hi);
      segs_.push_back(s);
    }
  }
  for (int a = 0; a < 3; ++a) n_[std::size_t(a)] = int(std::ceil((hi_[a] - lo_[a]) / cell_)) + 1;
  grid_.assign(std::size_t(n_[0]) * n_[1] * n_[2], {});
  for (int si = 0; si < int(segs_.size()); ++si) {
    const Seg& s = segs_[std::size_t(si)];
    int a0[3], a1[3];
    for (int a = 0; a < 3; ++a) {
      a0[a] = std::max(0, int(std::floor((s.lo[a] - lo_[a]) / cell_)));
      a1[a] = std::min(n_[std::size_t(a)] - 1, int(std::floor((s.hi[a] - lo_[a]) / cell_)));
    }
    for (int z = a0[2]; z <= a1[2]; ++z)
      for (int y = a0[1]; y <= a1[1]; ++y)
        for (int x = a0[0]; x <= a1[0]; ++x)
          grid_[(std::size_t(z) * n_[1] + y) * n_[0] + x].push_back(si);
  }
}

double CageField::segValue(const Seg& s, const Vec3& p, double* uOut) const {
  const Curve& c = m_.curves[std::size_t(s.curve)];
  const std::size_t i = std::size_t(s.i);
  const Vec3& c0 = c.c[i];
  const Vec3 d = c.c[i + 1] - c0;
  const double L2 = d.squaredNorm();
  double t = L2 > 0 ? (p - c0).dot(d) / L2 : 0.0;
  const bool lo = t <= 0, hi = t >= 1;
  t = std::clamp(t, 0.0, 1.0);
  const Vec3 v = p - (c0 + t * d);
  const Vec3 n = (1 - t) * c.n[i] + t * c.n[i + 1], b = (1 - t) * c.b[i] + t * c.b[i + 1];
  const double ra = (1 - t) * c.ra[i] + t * c.ra[i + 1], rb = (1 - t) * c.rb[i] + t * c.rb[i + 1];
  const double vn = v.dot(n) / ra, vb = v.dot(b) / rb;
  double q = vn * vn + vb * vb;
  if ((lo || hi) && L2 > 0) {
    const double vt = v.dot(d) / std::sqrt(L2);
    const bool end = (lo && i == 0) || (hi && i + 2 == c.c.size());
    const double rt = end ? (c.rib == 0 ? 0.8 * rb : rb) : std::max(ra, rb);
    q += (vt / rt) * (vt / rt);
  }
  if (uOut) *uOut = (1 - t) * c.u[i] + t * c.u[i + 1];
  return (std::sqrt(q) - 1) * std::min(ra, rb);
}

double CageField::operator()(const Vec3& p) const {
  int a[3];
  for (int k = 0; k < 3; ++k) {
    a[k] = int(std::floor((p[k] - lo_[k]) / cell_));
    if (a[k] < 0 || a[k] >= n_[std::size_t(k)]) return 1.0;
  }
  const auto& list = grid_[(std::size_t(a[2]) * n_[1] + a[1]) * n_[0] + a[0]];
  if (list.empty()) return 1.0;
  constexpr int kMax = 32;
  double best[kMax];
  std::fill(best, best + kMax, std::numeric_limits<double>::infinity());
  for (int si : list) {
    const Seg& s = segs_[std::size_t(si)];
    const double v = segValue(s, p);
    if (v < best[s.curve]) best[s.curve] = v;
  }
  const double k = m_.blend;
  double r = std::numeric_limits<double>::infinity();
  for (int c = 0; c < int(m_.curves.size()) && c < kMax; ++c) {
    const double v = best[c];
    if (!std::isfinite(v)) continue;
    if (!std::isfinite(r)) { r = v; continue; }
    const double h = k > 0 ? std::max(k - std::abs(r - v), 0.0) / k : 0.0;  // k = 0: plain union
    r = std::min(r, v) - h * h * k * 0.25;
  }
  return std::isfinite(r) ? std::min(r, 1.0 + k) : 1.0;
}

std::pair<int, double> CageField::nearest(const Vec3& p) const {
  int a[3];
  for (int k = 0; k < 3; ++k) a[k] = std::clamp(int(std::floor((p[k] - lo_[k]) / cell_)), 0, n_[std::size_t(k)] - 1);
  const auto& list = grid_[(std::size_t(a[2]) * n_[1] + a[1]) * n_[0] + a[0]];
  double best = std::numeric_limits<double>::infinity(), bu = 0;
  int bc = -1;
  auto consider = [&](const Seg& s) {
    double u;
    const double v = segValue(s, p, &u);
    if (v < best) { best = v; bc = s.curve; bu = u; }
  };
  for (int si : list) consider(segs_[std::size_t(si)]);
  if (bc < 0)
    for (const Seg& s : segs_) consider(s);
  return {bc, bu};
}

}  // namespace pectus::ribcage
