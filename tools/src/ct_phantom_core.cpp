#include "pectus/phantom/ct_phantom_core.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <random>

#include "pectus/errors.h"
#include "pectus/ribcage/ribcage_model.h"

namespace pectus::phantom {

using Vec3 = Eigen::Vector3d;

const char* axesName(Axes a) {
  switch (a) {
    case Axes::RAS: return "RAS";
    case Axes::LPS: return "LPS";
    default: return "native";
  }
}

Eigen::Matrix3d axesRotation(Axes a) {
  // project frame: +x left, +y anterior, +z superior
  switch (a) {
    case Axes::RAS: return Vec3(-1, 1, 1).asDiagonal();
    case Axes::LPS: return Vec3(1, -1, 1).asDiagonal();
    default: return Eigen::Matrix3d::Identity();
  }
}

namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// One structure: a label, its precedence where structures overlap (lower wins), an implicit function
// (negative inside) and the boxes outside which it is positive.
struct Shape {
  int label = 0, rank = 0;
  std::function<double(const Vec3&)> f;
  std::vector<std::pair<Vec3, Vec3>> boxes;
};

enum Rank { kSternum = 0, kBone = 1, kCartilage = 2, kVertebra = 3, kScapula = 4 };

std::vector<std::pair<Vec3, Vec3>> fieldBoxes(const ribcage::CageField& f) {
  std::vector<std::pair<Vec3, Vec3>> b;
  for (const auto& s : f.segments()) b.emplace_back(s.lo, s.hi);
  return b;
}

}  // namespace

Phantom makePhantom(const PhantomParams& p, const std::function<void(const char*)>& progress) {
  auto say = [&](const char* w) { if (progress) progress(w); };
  for (int a = 0; a < 3; ++a)
    if (!(p.spacing[a] >= 0.2 && p.spacing[a] <= 5))
      throw InputError("voxel spacing must be in [0.2, 5] mm along each axis, got " + std::to_string(p.spacing[a]));
  Phantom out;
  auto t0 = Clock::now();
  say("calibrating the cage model");
  std::vector<Landmark> lms;
  const ribcage::CageModel model = ribcage::buildCalibratedModel(p.cage, &out.stats, &lms);
  out.secondsModel = secondsSince(t0);
  t0 = Clock::now();
  say("building the structures");

  // --- the structures' fields (fields keep a reference to the model, which outlives them here)
  std::vector<std::unique_ptr<ribcage::CageField>> fields;
  std::vector<Shape> shapes;
  const int nCurves = int(model.curves.size());
  for (int ci = 0; ci < nCurves; ++ci) {
    const ribcage::Curve& c = model.curves[std::size_t(ci)];
    if (c.rib <= 0) continue;
    const ribcage::Curve* cp = &c;
    fields.push_back(std::make_unique<ribcage::CageField>(
        model, 5.0, [cp](const ribcage::Curve& cc, int i) { return &cc == cp && cc.u[std::size_t(i)] < cc.uCartilage; }));
    const ribcage::CageField* f = fields.back().get();
    shapes.push_back({ribLabel(c.side, c.rib), kBone, [f](const Vec3& q) { return (*f)(q); }, fieldBoxes(*f)});
  }
  {
    fields.push_back(std::make_unique<ribcage::CageField>(
        model, 5.0, [](const ribcage::Curve& c, int i) { return c.rib > 0 && c.u[std::size_t(i) + 1] > c.uCartilage; }));
    const ribcage::CageField* f = fields.back().get();
    shapes.push_back({kCartilageLabel, kCartilage, [f](const Vec3& q) { return (*f)(q); }, fieldBoxes(*f)});
    fields.push_back(std::make_unique<ribcage::CageField>(model, 5.0, [](const ribcage::Curve& c, int) { return c.rib == 0; }));
    f = fields.back().get();
    shapes.push_back({kSternumLabel, kSternum, [f](const Vec3& q) { return (*f)(q); }, fieldBoxes(*f)});
  }

  const double sMax = p.spacing.maxCoeff();
  // vertebral bodies: elliptic cylinders through the rib pair's costovertebral joints (heads on the lateral
  // surface, 0.25 voxel inside), anterior surface at y = 0, one level high minus a disc gap of 1.5 voxels
  const double gap = 1.5 * p.spacing[2];
  for (int k = 1; k <= model.ribPairs; ++k) {
    double xh = 0, yh = 0, zh = 0;
    int n = 0;
    for (const auto& c : model.curves)
      if (c.rib == k) {
        xh = std::max(xh, std::abs(c.c.front().x()));
        yh += c.c.front().y();
        zh += c.c.front().z();
        ++n;
      }
    yh /= n;
    zh /= n;
    const double rx = xh + 0.25 * p.spacing[0], ry = std::max(std::abs(yh), 4.0), yc = yh;
    const double hz = 0.5 * (model.delta - gap);
    const Vec3 lo(-rx, yc - ry, zh - hz), hi(rx, yc + ry, zh + hz);
    shapes.push_back({vertebraLabel(k), kVertebra,
                      [=](const Vec3& q) {
                        const double e = (std::hypot(q.x() / rx, (q.y() - yc) / ry) - 1) * std::min(rx, ry);
                        return std::max(e, std::abs(q.z() - zh) - hz);
                      },
                      {{lo, hi}}});
  }

  // scapulae: a sector of an elliptic shell around the cage, posterior-lateral, from rib 2 to rib 7
  {
    const double L = model.d.spineHeight, dl = model.delta;
    const double zTop = L - 1.3 * dl, zBot = L - 7.3 * dl;
    const double yc = 0.1 * model.d.chestDepth;
    const double clear = 3.0 + 1.5 * sMax, thick = std::max(3.0, 2.0 * sMax);
    for (int side = 1; side <= 2; ++side) {
      const double sg = side == 2 ? 1.0 : -1.0;
      double ax = 0, ymin = 1e30;
      for (const auto& c : model.curves)
        if (c.rib > 0 && c.side == side)
          for (std::size_t i = 0; i < c.c.size(); ++i)
            if (c.c[i].z() > zBot - 30 && c.c[i].z() < zTop + 30) {
              ax = std::max(ax, std::abs(c.c[i].x()));
              ymin = std::min(ymin, c.c[i].y());
            }
      const double ay = yc - ymin, amin = std::min(ax, ay);
      auto rho = [=](const Vec3& q) { return std::hypot(sg * q.x() / ax, (q.y() - yc) / ay); };
      // inner radius: every rib point near the plate at least (tube radius + clearance) away (rho is
      // 1/amin-Lipschitz); near: within 40 mm in z and behind the lateral extreme (angle below 0; the plate
      // ends 25 degrees before it, and the anterior ribs and cartilages, off the ellipse, are far from it)
      const double pi = 3.14159265358979323846;
      double s0 = 0;
      for (const auto& c : model.curves)
        if (c.rib > 0 && c.side == side)
          for (std::size_t i = 0; i < c.c.size(); ++i)
            if (c.c[i].z() > zBot - 40 && c.c[i].z() < zTop + 40 &&
                std::atan2((c.c[i].y() - yc) / ay, sg * c.c[i].x() / ax) < 0.0)
              s0 = std::max(s0, rho(c.c[i]) + (std::max(c.ra[i], c.rb[i]) + model.spacing + clear) / amin);
      const double s1 = s0 + thick / amin;
      // angle on the scaled circle: 0 lateral, -pi/2 posterior; the plate narrows downwards
      auto sector = [=](double z) {
        const double t = std::clamp((zTop - z) / (zTop - zBot), 0.0, 1.0);
        return std::array<double, 2>{(-78 + 18 * t) * pi / 180, (-28 - 12 * t) * pi / 180};
      };
      auto fn = [=](const Vec3& q) {
        const double r = rho(q);
        const double th = std::atan2((q.y() - yc) / ay, sg * q.x() / ax);
        const auto s = sector(q.z());
        const double radial = std::max(s0 - r, r - s1) * amin;
        const double angular = std::max(s[0] - th, th - s[1]) * s1 * amin;
        const double vertical = std::max(zBot - q.z(), q.z() - zTop);
        return std::max({radial, angular, vertical});
      };
      Vec3 lo = Vec3::Constant(1e30), hi = Vec3::Constant(-1e30);
      for (int a = 0; a <= 40; ++a) {
        const double th = (-80 + 55 * a / 40.0) * pi / 180;
        for (double r : {s0, s1}) {
          const Vec3 q(sg * r * ax * std::cos(th), yc + r * ay * std::sin(th), 0);
          lo = lo.cwiseMin(q);
          hi = hi.cwiseMax(q);
        }
      }
      lo.z() = zBot;
      hi.z() = zTop;
      lo -= Vec3::Constant(1);
      hi += Vec3::Constant(1);
      shapes.push_back({side == 2 ? kScapulaLeftLabel : kScapulaRightLabel, kScapula, fn, {{lo, hi}}});
    }
  }

  // --- the grid: i -> +x (left), j -> -y (posterior), k -> +z (superior), in the project frame
  Vec3 lo = Vec3::Constant(1e30), hi = Vec3::Constant(-1e30);
  for (const auto& s : shapes)
    for (const auto& b : s.boxes) {
      lo = lo.cwiseMin(b.first);
      hi = hi.cwiseMax(b.second);
    }
  lo -= Vec3::Constant(p.margin);
  hi += Vec3::Constant(p.margin);
  std::array<int, 3> dims{};
  for (int a = 0; a < 3; ++a) dims[std::size_t(a)] = int(std::ceil((hi[a] - lo[a]) / p.spacing[a])) + 1;
  const double nvox = double(dims[0]) * dims[1] * dims[2];
  if (nvox > 2.0e9) throw InputError("the phantom grid would have " + std::to_string(nvox) + " voxels; use a coarser spacing");
  const Vec3 origin(lo.x(), hi.y(), lo.z());  // centre of voxel (0, 0, 0)
  const Vec3 step(p.spacing[0], -p.spacing[1], p.spacing[2]);
  Eigen::Matrix4d voxToCage = Eigen::Matrix4d::Identity();
  voxToCage.topLeftCorner<3, 3>() = step.asDiagonal();
  voxToCage.block<3, 1>(0, 3) = origin;
  out.cageToScanner.topLeftCorner<3, 3>() = axesRotation(p.axes);
  out.cageToScanner.block<3, 1>(0, 3) = p.offset;
  patient::LabelVolume& v = out.volume;
  v.dims = dims;
  v.voxelToMm = out.cageToScanner * voxToCage;
  v.labels.assign(std::size_t(nvox), 0);

  // --- rasterise, one k slice per task; a voxel is evaluated once per structure whose boxes hold it
  say("rasterising");
  const int nx = dims[0], ny = dims[1], nz = dims[2], nS = int(shapes.size());
#pragma omp parallel
  {
    std::vector<int> stamp(std::size_t(nx) * ny, -1);
    std::vector<float> score(std::size_t(nx) * ny);
    std::vector<std::int8_t> rank(std::size_t(nx) * ny);
#pragma omp for schedule(dynamic, 1)
    for (int k = 0; k < nz; ++k) {
      const double z = origin.z() + k * step.z();
      std::fill(rank.begin(), rank.end(), std::int8_t(127));
      std::int32_t* lab = v.labels.data() + std::size_t(k) * nx * ny;
      for (int s = 0; s < nS; ++s) {
        const Shape& sh = shapes[std::size_t(s)];
        const int gen = k * nS + s;
        for (const auto& b : sh.boxes) {
          if (z < b.first.z() || z > b.second.z()) continue;
          const int i0 = std::max(0, int(std::ceil((b.first.x() - origin.x()) / step.x())));
          const int i1 = std::min(nx - 1, int(std::floor((b.second.x() - origin.x()) / step.x())));
          const int j0 = std::max(0, int(std::ceil((origin.y() - b.second.y()) / p.spacing[1])));
          const int j1 = std::min(ny - 1, int(std::floor((origin.y() - b.first.y()) / p.spacing[1])));
          for (int j = j0; j <= j1; ++j)
            for (int i = i0; i <= i1; ++i) {
              const std::size_t q = std::size_t(i) + std::size_t(nx) * std::size_t(j);
              if (stamp[q] == gen) continue;
              stamp[q] = gen;
              if (sh.rank > rank[q]) continue;
              const double f = sh.f(Vec3(origin.x() + i * step.x(), origin.y() + j * step.y(), z));
              if (!(f < 0)) continue;
              if (sh.rank < rank[q] || f < score[q]) {
                rank[q] = std::int8_t(sh.rank);
                score[q] = float(f);
                lab[q] = sh.label;
              }
            }
        }
      }
    }
  }

  // --- stray voxels: one rib's label, single voxels at least 10 mm from anything
  std::mt19937 rng(p.seed);
  auto uni = [&](int n) { return int((std::uint64_t(rng()) * std::uint64_t(n)) >> 32); };
  out.strayLabel = ribLabel(1 + uni(2), 1 + uni(model.ribPairs));
  const double clearMm = 10.0;
  std::array<int, 3> rad{};
  for (int a = 0; a < 3; ++a) rad[std::size_t(a)] = int(std::ceil(clearMm / p.spacing[a]));
  for (int attempt = 0; attempt < 20000 && int(out.strays.size()) < p.strayVoxels; ++attempt) {
    const std::array<int, 3> c{uni(nx), uni(ny), uni(nz)};
    bool ok = true;
    for (int dk = -rad[2]; ok && dk <= rad[2]; ++dk)
      for (int dj = -rad[1]; ok && dj <= rad[1]; ++dj)
        for (int di = -rad[0]; ok && di <= rad[0]; ++di) {
          const int i = c[0] + di, j = c[1] + dj, k = c[2] + dk;
          if (i < 0 || j < 0 || k < 0 || i >= nx || j >= ny || k >= nz) continue;
          if (v.at(i, j, k) == 0) continue;
          const double d2 = std::pow(di * p.spacing[0], 2) + std::pow(dj * p.spacing[1], 2) + std::pow(dk * p.spacing[2], 2);
          if (d2 < clearMm * clearMm) ok = false;
        }
    if (!ok) continue;
    v.labels[std::size_t(c[0]) + std::size_t(nx) * (std::size_t(c[1]) + std::size_t(ny) * std::size_t(c[2]))] = out.strayLabel;
    out.strays.push_back(c);
  }

  // --- names of the labels present, landmarks in the scanner frame
  for (const auto& c : model.curves)
    if (c.rib > 0) v.names[ribLabel(c.side, c.rib)] = std::string(c.side == 2 ? "rib_left_" : "rib_right_") + std::to_string(c.rib);
  v.names[kSternumLabel] = "sternum";
  v.names[kCartilageLabel] = "costal_cartilages";
  for (int k = 1; k <= model.ribPairs; ++k) v.names[vertebraLabel(k)] = "vertebrae_T" + std::to_string(k);
  v.names[kScapulaLeftLabel] = "scapula_left";
  v.names[kScapulaRightLabel] = "scapula_right";
  const std::vector<int> present = v.presentLabels();
  for (auto it = v.names.begin(); it != v.names.end();)
    it = std::binary_search(present.begin(), present.end(), it->first) ? std::next(it) : v.names.erase(it);
  for (const auto& l : lms)
    out.landmarks.push_back({l.code, out.cageToScanner.topLeftCorner<3, 3>() * l.p + out.cageToScanner.block<3, 1>(0, 3)});
  out.secondsRaster = secondsSince(t0);
  return out;
}

}  // namespace pectus::phantom
