// Ferguson bicubic envelope (thesis 6.3.2, Figs. 6-8..6-10, eqs. 6-1..6-3).
//
// The surface: (n+1) x m key points P(i,j) = O + L(i,j) (cos phi_j, sin phi_j) at heights
// z_i = zLo + i (zHi-zLo)/n, phi_j = 2 pi j / m; each patch is a Ferguson bicubic (Hermite, zero
// twists) with the key points' tangents by central differences (one-sided on the end rings), so
// the patches join with C1 continuity and the z of the surface is linear in u.
#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

#include "pectus/errors.h"
#include "pectus/grid_cell.h"
#include "pectus/vol/thoracic_volume.h"

namespace pectus::vol {

namespace {
constexpr double kPi = 3.14159265358979323846;
inline double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }
inline void hermite(double t, double h[4], double dh[4]) {
  const double t2 = t * t, t3 = t2 * t;
  h[0] = 2 * t3 - 3 * t2 + 1, h[1] = -2 * t3 + 3 * t2, h[2] = t3 - 2 * t2 + t, h[3] = t3 - t2;
  if (dh) dh[0] = 6 * t2 - 6 * t, dh[1] = -6 * t2 + 6 * t, dh[2] = 3 * t2 - 4 * t + 1, dh[3] = 3 * t2 - 2 * t;
}

// The u-combination of a patch's geometry matrix (xy only): A_b(u) and dA_b/du
struct Column {
  Eigen::Vector2d A[4], dA[4];
};

struct Surf {
  const Envelope& e;
  double dz;
  std::vector<double> c, s;
  double arc;
  explicit Surf(const Envelope& env)
      : e(env), dz((env.zHi - env.zLo) / env.n), c(env.m), s(env.m), arc(4 * std::tan(kPi / (2 * env.m))) {
    for (int j = 0; j < e.m; ++j) c[j] = std::cos(e.phi[j]), s[j] = std::sin(e.phi[j]);
  }
  int wrap(int j) const { return ((j % e.m) + e.m) % e.m; }
  Eigen::Vector2d P(int i, int j) const {
    j = wrap(j);
    const double L = e.L[std::size_t(i) * e.m + j];
    return e.axis + L * Eigen::Vector2d(c[j], s[j]);
  }
  Eigen::Vector2d Pu(int i, int j) const {
    if (i == 0) return P(1, j) - P(0, j);
    if (i == e.n) return P(e.n, j) - P(e.n - 1, j);
    return 0.5 * (P(i + 1, j) - P(i - 1, j));
  }
  // tangent around the axis, per unit v: the radius' derivative (fourth-order central difference) along e_r plus the circular
  // arc's Hermite tangent 4 tan(dphi/4) L along e_phi (exact midpoint for a circle; C1 as it is shared)
  Eigen::Vector2d Pv(int i, int j) const {
    j = wrap(j);
    const double L = e.L[std::size_t(i) * e.m + j];
    const double* row = &e.L[std::size_t(i) * e.m];
    const double dL = e.m >= 5 ? (8 * (row[wrap(j + 1)] - row[wrap(j - 1)]) - (row[wrap(j + 2)] - row[wrap(j - 2)])) / 12.0
                               : 0.5 * (row[wrap(j + 1)] - row[wrap(j - 1)]);
    return dL * Eigen::Vector2d(c[j], s[j]) + arc * L * Eigen::Vector2d(-s[j], c[j]);
  }
  Column column(int i, int j, double u) const {
    double h[4], dh[4];
    hermite(u, h, dh);
    const Eigen::Vector2d p00 = P(i, j), p10 = P(i + 1, j), p01 = P(i, j + 1), p11 = P(i + 1, j + 1);
    const Eigen::Vector2d u00 = Pu(i, j), u10 = Pu(i + 1, j), u01 = Pu(i, j + 1), u11 = Pu(i + 1, j + 1);
    const Eigen::Vector2d v00 = Pv(i, j), v10 = Pv(i + 1, j), v01 = Pv(i, j + 1), v11 = Pv(i + 1, j + 1);
    Column C;
    C.A[0] = h[0] * p00 + h[1] * p10 + h[2] * u00 + h[3] * u10;
    C.A[1] = h[0] * p01 + h[1] * p11 + h[2] * u01 + h[3] * u11;
    C.A[2] = h[0] * v00 + h[1] * v10;
    C.A[3] = h[0] * v01 + h[1] * v11;
    C.dA[0] = dh[0] * p00 + dh[1] * p10 + dh[2] * u00 + dh[3] * u10;
    C.dA[1] = dh[0] * p01 + dh[1] * p11 + dh[2] * u01 + dh[3] * u11;
    C.dA[2] = dh[0] * v00 + dh[1] * v10;
    C.dA[3] = dh[0] * v01 + dh[1] * v11;
    return C;
  }
  // radius of the surface along the ray from the axis at angle (cos a, sin a), height z: Newton-Raphson in v
  double ray(double ca, double sa, double angle, double z, int* its = nullptr) const {
    const double dphi = 2 * kPi / e.m;
    double t = (z - e.zLo) / dz;
    int i = clampedCell(t, e.n);
    const double u = std::clamp(t - i, 0.0, 1.0);
    double a = angle / dphi;
    int j = int(std::floor(a));
    double v = a - j;
    j = wrap(j);
    const Eigen::Vector2d d(ca, sa);
    Column C = column(i, j, u);
    int k = 0, switches = 0;
    Eigen::Vector2d S;
    for (; k < 30; ++k) {
      double h[4], dh[4];
      hermite(v, h, dh);
      S = h[0] * C.A[0] + h[1] * C.A[1] + h[2] * C.A[2] + h[3] * C.A[3];
      const Eigen::Vector2d Sv = dh[0] * C.A[0] + dh[1] * C.A[1] + dh[2] * C.A[2] + dh[3] * C.A[3];
      const double f = cross2(d, S - e.axis), fp = cross2(d, Sv);
      if (std::abs(fp) < 1e-300) break;
      const double dv = f / fp;
      v -= dv;
      if ((v < -1e-9 || v > 1 + 1e-9) && switches < 4) {
        ++switches;
        if (v < 0) j = wrap(j - 1), v += 1;
        else j = wrap(j + 1), v -= 1;
        C = column(i, j, u);
        continue;
      }
      if (std::abs(dv) < 1e-12) {
        hermite(v, h, nullptr);
        S = h[0] * C.A[0] + h[1] * C.A[1] + h[2] * C.A[2] + h[3] * C.A[3];
        break;
      }
    }
    if (its) *its = k;
    return d.dot(S - e.axis);
  }
};

const double kGx[5] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831, 0.9061798459386640};
const double kGw[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889, 0.4786286704993665, 0.2369268850561891};
}  // namespace

Eigen::Vector3d Envelope::key(int i, int j) const {
  const double L0 = L[std::size_t(i) * m + j];
  return {axis.x() + L0 * std::cos(phi[j]), axis.y() + L0 * std::sin(phi[j]), zLo + i * (zHi - zLo) / n};
}

Eigen::Vector3d Envelope::eval(int i, int j, double u, double v, Eigen::Vector3d* Su, Eigen::Vector3d* Sv) const {
  Surf sf(*this);
  const Column C = sf.column(i, j, u);
  double h[4], dh[4];
  hermite(v, h, dh);
  Eigen::Vector2d S(0, 0), SU(0, 0), SV(0, 0);
  for (int b = 0; b < 4; ++b) S += h[b] * C.A[b], SU += h[b] * C.dA[b], SV += dh[b] * C.A[b];
  const double dz = (zHi - zLo) / n;
  if (Su) *Su = {SU.x(), SU.y(), dz};
  if (Sv) *Sv = {SV.x(), SV.y(), 0.0};
  return {S.x(), S.y(), zLo + (i + u) * dz};
}

double Envelope::rayRadius(double angle, double z, int* iterations) const {
  Surf sf(*this);
  double a = std::fmod(angle, 2 * kPi);
  if (a < 0) a += 2 * kPi;
  return sf.ray(std::cos(a), std::sin(a), a, z, iterations);
}

double Envelope::volume() const {
  // eq. 6-3 with the origin on the axis at zLo: V = 1/3 [ lateral integral of r.(Sv x Su) + top cap ]
  // (the bottom cap lies in the plane through the origin and contributes 0)
  Surf sf(*this);
  const double dzr = (zHi - zLo) / n;
  const Eigen::Vector3d O(axis.x(), axis.y(), zLo + row0 * dzr);
  double lateral = 0;
  for (int i = row0; i < row1; ++i)
    for (int j = 0; j < m; ++j)
      for (int a = 0; a < 5; ++a) {
        const double u = 0.5 * (kGx[a] + 1);
        const Column C = sf.column(i, j, u);
        for (int b = 0; b < 5; ++b) {
          const double v = 0.5 * (kGx[b] + 1);
          double h[4], dh[4];
          hermite(v, h, dh);
          Eigen::Vector2d S(0, 0), SU(0, 0), SV(0, 0);
          for (int k = 0; k < 4; ++k) S += h[k] * C.A[k], SU += h[k] * C.dA[k], SV += dh[k] * C.A[k];
          const double dz = (zHi - zLo) / n;
          const Eigen::Vector3d r(S.x() - O.x(), S.y() - O.y(), (i - row0 + u) * dz);
          const Eigen::Vector3d su(SU.x(), SU.y(), dz), sv(SV.x(), SV.y(), 0);
          lateral += 0.25 * kGw[a] * kGw[b] * r.dot(sv.cross(su));
        }
      }
  // top cap area by Green's theorem along the top boundary curve (u = 1 of the last patch row)
  double area = 0;
  for (int j = 0; j < m; ++j) {
    const Column C = sf.column(row1 - 1, j, 1.0);
    for (int b = 0; b < 5; ++b) {
      const double v = 0.5 * (kGx[b] + 1);
      double h[4], dh[4];
      hermite(v, h, dh);
      Eigen::Vector2d S(0, 0), SV(0, 0);
      for (int k = 0; k < 4; ++k) S += h[k] * C.A[k], SV += dh[k] * C.A[k];
      area += 0.5 * kGw[b] * 0.5 * cross2(S - axis, SV);
    }
  }
  return (lateral + (row1 - row0) * dzr * area) / 3.0;
}

Soup Envelope::tessellate(int t) const {
  t = std::max(1, t);
  Soup s;
  const int nr = row1 - row0, rows = nr * t + 1, cols = m * t;
  s.V.reserve(std::size_t(rows) * cols + 2);
  for (int I = 0; I < rows; ++I) {
    const int i = std::min(I / t, nr - 1);
    const double u = double(I - i * t) / t;
    for (int J = 0; J < cols; ++J) s.V.push_back(eval(row0 + i, J / t, u, double(J % t) / t));
  }
  const int bot = int(s.V.size());
  const double dzr = (zHi - zLo) / n;
  s.V.push_back({axis.x(), axis.y(), zLo + row0 * dzr});
  s.V.push_back({axis.x(), axis.y(), zLo + row1 * dzr});
  const int top = bot + 1;
  auto id = [&](int I, int J) { return I * cols + ((J % cols) + cols) % cols; };
  for (int I = 0; I + 1 < rows; ++I)
    for (int J = 0; J < cols; ++J) {
      s.F.push_back({id(I, J), id(I, J + 1), id(I + 1, J + 1)});
      s.F.push_back({id(I, J), id(I + 1, J + 1), id(I + 1, J)});
    }
  for (int J = 0; J < cols; ++J) {
    s.F.push_back({bot, id(0, J + 1), id(0, J)});
    s.F.push_back({top, id(rows - 1, J), id(rows - 1, J + 1)});
  }
  return s;
}

namespace {
struct Sample {
  double z, angle, r, c, s;
};

// The patch grid: m columns around the axis; n rows, the measured nLong plus one guard row beyond each end
// of the range (the cage goes on there: the measured end rings are not free edges that could dip into a
// gap); the outermost rings are tied to their inner neighbours, the volume is integrated over the measured
// rows only. B x B bins per patch keep its samples.
struct Grid {
  int m, B, n;
  double dz, dphi, ezLo, ezHi;
  int keys() const { return (n + 1) * m; }
  std::size_t patches() const { return std::size_t(n) * m; }
  int key(int i, int j) const { return i * m + ((j % m) + m) % m; }  ///< key point (ring i, column j mod m)
};

Grid gridFor(const Range& range, const EnvelopeParams& p) {
  Grid g;
  g.m = p.mAround, g.B = std::max(1, p.binsPerPatch), g.n = p.nLong + 2;
  g.dz = (range.zHi - range.zLo) / p.nLong, g.dphi = 2 * kPi / g.m;
  g.ezLo = range.zLo - g.dz, g.ezHi = range.zHi + g.dz;
  return g;
}

// angle of d around the axis in [0, 2 pi)
double angleOf(const Eigen::Vector2d& d) {
  double a = std::atan2(d.y(), d.x());
  if (a < 0) a += 2 * kPi;
  return a;
}

// the bounding box (x, y) of the faces' vertices in the range, whose centre is the axis; throws when there
// are none or the box has no extent
void boxInRange(const Soup& soup, const Range& range, Eigen::Vector2d& lo, Eigen::Vector2d& hi) {
  lo = Eigen::Vector2d(1e300, 1e300), hi = Eigen::Vector2d(-1e300, -1e300);
  for (const auto& f : soup.F)
    for (int k = 0; k < 3; ++k) {
      const auto& v = soup.V[f[k]];
      if (v.z() >= range.zLo && v.z() <= range.zHi) lo = lo.cwiseMin(v.head<2>()), hi = hi.cwiseMax(v.head<2>());
    }
  if (!(hi.x() >= lo.x())) {
    std::ostringstream o;
    o << "no geometry in the measured range: the layer has no vertex between z = " << range.zLo << " and z = "
      << range.zHi << " mm, the envelope cannot touch anything (check the range or the landmarks)";
    throw InputError(o.str());
  }
  if (std::max(hi.x() - lo.x(), hi.y() - lo.y()) < 1e-6)
    throw InputError("degenerate axis: the geometry in the measured range has no extent across the long axis (z)");
}

// samples: the used vertices within the grid's z plus points inside faces larger than a bin (so that
// sparse meshes bound the surface), in cylindrical coordinates about the axis
std::vector<Sample> collectSamples(const Soup& soup, const Grid& g, const Eigen::Vector2d& axis, double rmaxBox) {
  std::vector<Sample> raw;
  auto addSample = [&](const Eigen::Vector3d& q) {
    if (q.z() < g.ezLo || q.z() > g.ezHi) return;
    const Eigen::Vector2d d = q.head<2>() - axis;
    const double r = d.norm();
    if (r < 1e-9) return;
    const double a = angleOf(d);
    raw.push_back({q.z(), a, r, d.x() / r, d.y() / r});
  };
  std::vector<char> used(soup.V.size(), 0);
  for (const auto& f : soup.F)
    for (int k = 0; k < 3; ++k) used[f[k]] = 1;
  for (std::size_t i = 0; i < soup.V.size(); ++i)
    if (used[i]) addSample(soup.V[i]);
  const double target = std::min(g.dz, g.dphi * rmaxBox) / g.B;
  for (const auto& f : soup.F) {
    const Eigen::Vector3d &a = soup.V[f[0]], &b = soup.V[f[1]], &c = soup.V[f[2]];
    if (std::max({a.z(), b.z(), c.z()}) < g.ezLo || std::min({a.z(), b.z(), c.z()}) > g.ezHi) continue;
    const double e = std::max({(a - b).norm(), (b - c).norm(), (c - a).norm()});
    if (e <= target) continue;
    const int q = int(std::min(64.0, std::ceil(e / target)));  // clamped before the cast (e / target can be 1e18)
    for (int x = 0; x <= q; ++x)
      for (int y = 0; x + y <= q; ++y) {
        if ((x == 0 && y == 0) || (x == q) || (y == q)) continue;
        addSample(a + (double(x) / q) * (b - a) + (double(y) / q) * (c - a));
      }
  }
  if (raw.empty())
    throw InputError("no geometry in the measured range: the envelope cannot touch anything");
  return raw;
}

// the samples reduced to the outermost one per (patch, bin), per patch outermost first, and which patch
// quarters hold a sample (for the singular key points)
struct PatchSamples {
  std::vector<std::vector<Sample>> perPatch;
  std::vector<char> quarter;  ///< per patch 4: (u >= 0.5) * 2 + (v >= 0.5)
  double rmax = 0;            ///< the largest sample radius
  int count = 0;
};

PatchSamples reduceSamples(const std::vector<Sample>& raw, const Grid& g) {
  const int B = g.B;
  const std::size_t P = g.patches();
  PatchSamples ps;
  std::vector<int> best(P * B * B, -1);
  ps.quarter.assign(P * 4, 0);
  for (std::size_t k = 0; k < raw.size(); ++k) {
    const auto& sm = raw[k];
    const double t = (sm.z - g.ezLo) / g.dz;
    const int i = clampedCell(t, g.n);
    const double u = std::clamp(t - i, 0.0, 1.0);
    const double a = sm.angle / g.dphi;
    const int j = clampedCell(a, g.m);
    const double v = std::clamp(a - j, 0.0, 1.0);
    const std::size_t pid = std::size_t(i) * g.m + j;
    ps.quarter[pid * 4 + (u >= 0.5 ? 2 : 0) + (v >= 0.5 ? 1 : 0)] = 1;
    const int bu = std::min(B - 1, int(u * B)), bv = std::min(B - 1, int(v * B));
    int& slot = best[(pid * B + bu) * B + bv];
    if (slot < 0 || raw[slot].r < sm.r) slot = int(k);
    ps.rmax = std::max(ps.rmax, sm.r);
  }
  ps.perPatch.resize(P);
  for (std::size_t pid = 0; pid < P; ++pid) {
    auto& mine = ps.perPatch[pid];
    for (int b = 0; b < B * B; ++b)
      if (best[pid * B * B + b] >= 0) mine.push_back(raw[best[pid * B * B + b]]), ++ps.count;
    std::sort(mine.begin(), mine.end(), [](const Sample& x, const Sample& y) { return x.r > y.r; });
  }
  return ps;
}

// The key points that move together: a singular key point (Fig. 6-10: no sample in the four patch
// quarters around it) is tied to a non-singular one and moves with it; each group is one radius.
struct KeyGroups {
  int singular = 0;                          ///< singular key points
  std::vector<int> roots;                    ///< the groups, by their non-singular key point
  std::vector<std::vector<int>> members;     ///< per root: the key points that move with it
  std::vector<std::vector<int>> affected;    ///< per root: the patches its members shape
};

// per key point: no sample in the four patch quarters around it; throws when every key point is singular
std::vector<char> singularKeys(const std::vector<char>& quarter, const Grid& g, int& count) {
  const int n = g.n, m = g.m;
  std::vector<char> singular(g.keys(), 0);
  count = 0;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j < m; ++j) {
      bool any = false;
      for (int di = -1; di <= 0; ++di)
        for (int dj = -1; dj <= 0; ++dj) {
          const int pi = i + di;
          if (pi < 0 || pi >= n) continue;
          const int pj = ((j + dj) % m + m) % m;
          const int qu = di == -1 ? 1 : 0, qv = dj == -1 ? 1 : 0;
          any = any || quarter[(std::size_t(pi) * m + pj) * 4 + qu * 2 + qv];
        }
      if (!any) singular[g.key(i, j)] = 1, ++count;
    }
  if (count == g.keys()) throw InputError("the envelope cannot touch anything: no key point has a sample around it");
  return singular;
}

// every singular key point tied to its closest non-singular key point along the circle (I-1 first), a fully
// singular ring to the nearest ring's key point in the same column; the end rings to their inner neighbours
std::vector<int> tieSingularKeys(const std::vector<char>& singular, const Grid& g) {
  const int n = g.n, m = g.m;
  auto kid = [&g](int i, int j) { return g.key(i, j); };
  std::vector<int> root(g.keys());
  for (int i = 1; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const int k = kid(i, j);
      root[k] = k;
      if (!singular[k]) continue;
      int found = -1;
      for (int d = 1; d <= m / 2 && found < 0; ++d) {
        if (!singular[kid(i, j - d)]) found = kid(i, j - d);
        else if (!singular[kid(i, j + d)]) found = kid(i, j + d);
      }
      for (int d = 1; d <= n && found < 0; ++d)
        for (int ii : {i - d, i + d}) {
          if (found >= 0 || ii < 1 || ii > n - 1) continue;
          for (int dd = 0; dd <= m / 2 && found < 0; ++dd) {
            if (!singular[kid(ii, j - dd)]) found = kid(ii, j - dd);
            else if (!singular[kid(ii, j + dd)]) found = kid(ii, j + dd);
          }
        }
      root[k] = found;
    }
  for (int j = 0; j < m; ++j) {
    root[kid(0, j)] = root[kid(1, j)];
    root[kid(n, j)] = root[kid(n - 1, j)];
  }
  return root;
}

KeyGroups groupKeys(const std::vector<char>& quarter, const Grid& g) {
  const int K = g.keys(), n = g.n, m = g.m;
  KeyGroups kg;
  const std::vector<char> singular = singularKeys(quarter, g, kg.singular);
  const std::vector<int> root = tieSingularKeys(singular, g);
  kg.members.resize(K);
  for (int k = 0; k < K; ++k) kg.members[root[k]].push_back(k);
  for (int k = 0; k < K; ++k)
    if (root[k] == k) kg.roots.push_back(k);
  // patches influenced by each group (rows i-2..i+1, columns j-3..j+2 of every member)
  kg.affected.resize(K);
  std::vector<int> stamp(g.patches(), -1);
  for (int r : kg.roots) {
    for (int k : kg.members[r]) {
      const int i = k / m, j = k % m;
      for (int pi = i - 2; pi <= i + 1; ++pi) {
        if (pi < 0 || pi >= n) continue;
        for (int pj = j - 3; pj <= j + 2; ++pj) {
          const int pid = pi * m + ((pj % m) + m) % m;
          if (stamp[pid] != r) stamp[pid] = r, kg.affected[r].push_back(pid);
        }
      }
    }
  }
  return kg;
}

// the key points that eq. 6-1 may smooth: not the guard rings nor the measured end planes (thesis), and
// not those around the lower end of the sternum
std::vector<char> smoothableKeys(const Grid& g, const Eigen::Vector2d& axis, const std::optional<Eigen::Vector3d>& sternumEnd) {
  std::vector<char> smoothable(g.keys(), 0);
  for (int i = 2; i < g.n - 1; ++i)
    for (int j = 0; j < g.m; ++j) smoothable[g.key(i, j)] = 1;
  if (sternumEnd) {
    const double a = angleOf(sternumEnd->head<2>() - axis);
    for (int i = 0; i <= g.n; ++i)
      for (int j = 0; j < g.m; ++j) {
        double da = std::abs(j * g.dphi - a);
        da = std::min(da, 2 * kPi - da);
        if (std::abs(g.ezLo + i * g.dz - sternumEnd->z()) <= g.dz && da <= g.dphi) smoothable[g.key(i, j)] = 0;
      }
  }
  return smoothable;
}

// The shrinking of the key points' radii onto the samples (Fig. 6-9): a group steps inward while no
// sample of the patches it shapes ends up outside the surface (cut), halving the step level by level.
class Shrink {
 public:
  Shrink(Envelope& env, const Grid& g, const PatchSamples& ps, const KeyGroups& kg, EnvelopeResult& res)
      : env_(env), g_(g), sf_(env), perPatch_(ps.perPatch), kg_(kg), res_(res), tol_(1e-7 * ps.rmax) {}

  // the start radius: 1.05 x the largest sample radius, raised by 20 % (at most 20 times) while it cuts
  double startRadius(double rmax) {
    std::vector<int> allPatches(g_.patches());
    std::iota(allPatches.begin(), allPatches.end(), 0);
    double R0 = 1.05 * rmax;
    env_.L.assign(g_.keys(), R0);
    for (int guard = 0; cutAny(allPatches) && guard < 20; ++guard) {
      R0 *= 1.2;
      env_.L.assign(g_.keys(), R0);
    }
    return R0;
  }

  // one step level: sweeps moving every group inward by `step` until each is held (it would cut, or
  // reach minL) or gains less than a quarter step; touched: the groups held by the cage
  void level(double step, double minL, const std::vector<char>* smoothable, std::vector<char>& touched) {
    std::vector<char> held(g_.keys(), 0);
    std::fill(touched.begin(), touched.end(), 0);
    int active = int(kg_.roots.size());
    for (int sweep = 0; active > 0 && sweep < 100000; ++sweep) {
      const std::vector<double> before = env_.L;
      for (int g : kg_.roots) {
        if (held[g]) continue;
        const double L0 = env_.L[g], L1 = L0 - step;
        if (L1 < minL) {
          held[g] = 1;
          continue;
        }
        setGroup(g, L1);
        if (cutAny(kg_.affected[g])) {
          setGroup(g, L0);
          held[g] = 1, touched[g] = 1;
        } else {
          ++res_.moves;
        }
      }
      if (smoothable) smooth(*smoothable);
      active = 0;
      for (int g : kg_.roots) {
        if (held[g]) continue;
        if (before[g] - env_.L[g] < 0.25 * step) held[g] = 1;
        else ++active;
      }
    }
  }

 private:
  // eq. 6-1: L' = mean of the three key points along z, taken only when it is larger and cuts nothing
  void smooth(const std::vector<char>& smoothable) {
    const std::vector<double> cur = env_.L;
    std::vector<int> raised;
    for (int g : kg_.roots) {
      if (!smoothable[g]) continue;
      if (ringMean(cur, g) > cur[g] + 1e-12) raised.push_back(g);
    }
    if (raised.empty()) return;
    for (int g : raised) setGroup(g, ringMean(cur, g));
    // a raise changes the tangents of the neighbours: keep it only if nothing is cut
    std::vector<int> stamp(g_.patches(), -1);
    std::vector<int> pids;
    for (int g : raised)
      for (int pid : kg_.affected[g])
        if (stamp[pid] != 0) stamp[pid] = 0, pids.push_back(pid);
    if (cutAny(pids)) env_.L = cur;
  }
  double ringMean(const std::vector<double>& L, int k) const {
    const int i = k / g_.m, j = k % g_.m;
    return (L[g_.key(i - 1, j)] + L[k] + L[g_.key(i + 1, j)]) / 3.0;
  }
  void setGroup(int g, double L) {
    for (int k : kg_.members[g]) env_.L[k] = L;
  }
  // a sample of the patch lies outside the surface
  bool cutIn(int pid) {
    for (const auto& sm : perPatch_[pid]) {
      ++res_.cutTests;
      if (sm.r > sf_.ray(sm.c, sm.s, sm.angle, sm.z) + tol_) return true;
    }
    return false;
  }
  bool cutAny(const std::vector<int>& pids) {
    for (int pid : pids)
      if (cutIn(pid)) return true;
    return false;
  }

  Envelope& env_;
  const Grid& g_;
  Surf sf_;
  const std::vector<std::vector<Sample>>& perPatch_;
  const KeyGroups& kg_;
  EnvelopeResult& res_;
  double tol_;
};
}  // namespace

EnvelopeResult fergusonEnvelope(const Soup& soup, const Range& range, const EnvelopeParams& p, const Progress& progress) {
  requireRange(range, "of the envelope");
  if (p.nLong < kPatchesLongRange.lo || p.mAround < kPatchesAroundRange.lo)
    throw InputError("the envelope needs at least " + std::to_string(int(kPatchesLongRange.lo)) + " x " +
                     std::to_string(int(kPatchesAroundRange.lo)) + " patches");
  if (!(p.minStep >= kMinStepRange.lo)) {
    std::ostringstream s;
    s << "the envelope's minimum step must be at least " << kMinStepRange.lo << " mm";
    throw InputError(s.str());
  }
  const Grid g = gridFor(range, p);
  Eigen::Vector2d lo, hi;
  boxInRange(soup, range, lo, hi);
  Envelope env;
  env.n = g.n, env.m = g.m, env.zLo = g.ezLo, env.zHi = g.ezHi, env.row0 = 1, env.row1 = g.n - 1;
  env.axis = 0.5 * (lo + hi);
  env.phi.resize(g.m);
  for (int j = 0; j < g.m; ++j) env.phi[j] = j * g.dphi;

  const std::vector<Sample> raw = collectSamples(soup, g, env.axis, 0.5 * (hi - lo).norm());
  if (progress) progress(5, "envelope samples");
  const PatchSamples ps = reduceSamples(raw, g);
  const KeyGroups kg = groupKeys(ps.quarter, g);

  EnvelopeResult res;
  Shrink shrink(env, g, ps, kg, res);
  const double R0 = shrink.startRadius(ps.rmax);
  const double minL = 0.02 * R0;
  const std::vector<char> smoothable = smoothableKeys(g, env.axis, p.sternumEnd);
  double step = p.initialStep > 0 ? p.initialStep : 0.25 * R0;
  std::vector<char> touched(g.keys());
  int totalLevels = 0;
  for (double s = step; s >= p.minStep; s *= 0.5) ++totalLevels;
  for (; step >= p.minStep; step *= 0.5) {
    ++res.levels;
    shrink.level(step, minL, p.smoothing ? &smoothable : nullptr, touched);
    if (progress) progress(10 + 85 * res.levels / std::max(1, totalLevels), "envelope convergence");
  }
  for (int r : kg.roots) res.touching += touched[r];
  if (res.touching == 0)
    throw InputError("the envelope cannot touch anything: every key point collapsed onto the axis (is the layer a "
                     "rib cage around the long axis z, and the range on it?)");
  res.samples = ps.count;
  res.singular = kg.singular;
  res.volume = env.volume();
  res.env = std::move(env);
  return res;
}

}  // namespace pectus::vol
