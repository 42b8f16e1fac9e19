#include "pectus/ribcage/ribcage.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

#include <vcg/complex/allocate.h>
#include <vcg/complex/append.h>
#include <vcg/complex/algorithms/clean.h>

#include "pectus/ribcage/marching_tets.h"
#include "pectus/mesh_simplify.h"
#include "pectus/errors.h"
#include "pectus/format.h"
#include "pectus/ribcage/ribcage_model.h"
#include "pectus/surface_cmesh.h"

namespace pectus::ribcage {

namespace {
using Vec3 = Eigen::Vector3d;
using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

std::string num(double v) { return significantText(v, 4); }
[[noreturn]] void bad(const std::string& name, const std::string& range, double got, const std::string& why = "") {
  throw InputError("parameter '" + name + "' must be " + range + ", got " + num(got) + (why.empty() ? "" : " (" + why + ")"));
}

// The dimensions by age, and what they are checked against (`pectus_ribcage_cli --anatomy` prints the
// model beside these figures; docs/validation.md, "Anatomy of the generated cage", shows the table):
// - the pectus index of the chest without funnel (depth = width / 2.45): 2.34 +- 0.26 at 3-6 years,
//   2.58 +- 0.24 at 7-11 and 2.63 +- 0.33 at 12-16 on CT (Wan et al., 75 normal children);
// - the sternum length, notch to xiphoid tip (7.4 vertebral levels, modelLevels): boys 5.616 x age + 60.4 mm,
//   girls -0.134 age^2 + 6.543 age + 56.8 mm (Li et al., Exp Ther Med 2022, 1,080 CTs, PMID 35978914);
// - the costal cartilage's share of the anterior rib, lateral point to sternum (ribCurve's uCartilage):
//   45-60 % at every level (Sandoz et al., Med Biol Eng Comput 2013;51(9):971-9, 48 children);
// - the 5th costal cartilage at age 8: 54 mm (the thesis' patient 1, Fig. 6-18).
// Chest width, spine height and the rib and sternum sections are the project's assumptions: no paediatric
// figure by age was found for them (the costal cartilage's section relative to the rib's: CartilageSection).
Dimensions fromAge(double age) {
  Dimensions d{};
  const double a = age - 5;
  d.chestWidth = 165 + 8 * a;
  d.chestDepth = d.chestWidth / 2.45;
  d.spineHeight = 150 + 10.8 * a;
  d.ribHeight = 7 + 0.33 * a;
  d.ribThickness = 4 + 0.17 * a;
  d.sternumWidth = 22 + 1.0 * a;
  d.sternumThickness = 8.5 + 0.3 * a;
  return d;
}

// first crossing of the field along origin + s*dir, s in [0, sMax]; sphere tracing (field is 1-Lipschitz)
template <class F>
bool firstHit(const F& f, const Vec3& o, const Vec3& dir, double sMax, double& sHit, bool wantInside = true) {
  double s = 0, fv = f(o);
  auto in = [&](double v) { return wantInside ? v < 0 : v > 0; };
  if (in(fv)) { sHit = 0; return true; }
  while (s < sMax) {
    const double step = std::max(0.9 * std::abs(fv), 0.02);
    const double s1 = s + step;
    const double f1 = f(o + s1 * dir);
    if (in(f1)) {
      double a = s, b = s1;
      for (int it = 0; it < 40; ++it) {
        const double mid = 0.5 * (a + b);
        if (in(f(o + mid * dir))) b = mid; else a = mid;
      }
      sHit = 0.5 * (a + b);
      return true;
    }
    s = s1;
    fv = f1;
  }
  return false;
}

struct Ap { double ap = 1e30, z = 0; };
Ap apDistance(const CageModel& m, const CageField& f, double dz) {
  Ap best;
  const double zHi = m.zNotch + 0.6 * m.d.sternumThickness, zLo = m.zTip - 3;
  const double yMax = 3 * m.d.chestDepth;
  for (double z = zLo; z <= zHi; z += dz)
    for (int xi = -2; xi <= 2; ++xi) {
      double s;
      if (firstHit(f, Vec3(double(xi), 0, z), Vec3::UnitY(), yMax, s) && s < best.ap) best = {s, z};
    }
  return best;
}

// widest inner transverse diameter: through the outer lateral extreme of each side, along x
double transverse(const CageModel& m, const CageField& f, double* xin = nullptr) {
  double x[2];
  for (int si = 0; si < 2; ++si) {
    const double sg = si == 0 ? -1 : 1;
    double bestExt = -1e30;
    Vec3 sup(0, 0, 0);
    for (const Curve& c : m.curves) {
      if (c.rib == 0) continue;
      for (std::size_t i = 0; i < c.c.size(); ++i) {
        const double nx = c.n[i].x(), bx = c.b[i].x();
        const double h = std::sqrt(std::pow(c.ra[i] * nx, 2) + std::pow(c.rb[i] * bx, 2));
        const double ext = sg * c.c[i].x() + h;
        if (ext > bestExt) {
          bestExt = ext;
          sup = c.c[i] + sg * (c.ra[i] * c.ra[i] * nx * c.n[i] + c.rb[i] * c.rb[i] * bx * c.b[i]) / std::max(h, 1e-9);
        }
      }
    }
    const Vec3 o(sg * (bestExt + 5), sup.y(), sup.z()), dir(-sg, 0, 0);
    double sIn = 0, sOut = 0;
    if (!firstHit(f, o, dir, 50, sIn)) throw InternalError("rib cage: lateral extreme not found");
    const Vec3 o2 = o + (sIn + 0.05) * dir;
    if (!firstHit(f, o2, dir, 60, sOut, false)) throw InternalError("rib cage: inner rib surface not found");
    x[si] = (o2 + sOut * dir).x();
  }
  if (xin) { xin[0] = x[0]; xin[1] = x[1]; }
  return x[1] - x[0];
}
}  // namespace

Dimensions validate(const RibCageParams& p) {
  Dimensions d{};
  if (p.fromAge) {
    if (!kAgeRange.contains(p.age)) bad("age", "in " + kAgeRange.text() + " years", p.age);
    d = fromAge(p.age);
  } else {
    if (!kChestWidthRange.contains(p.chestWidth)) bad("chestWidth", "in " + kChestWidthRange.text() + " mm", p.chestWidth);
    const ParamRange depth{kChestDepthShare.lo * p.chestWidth, kChestDepthShare.hi * p.chestWidth};
    if (!depth.contains(p.chestDepth))
      bad("chestDepth", "in [" + num(depth.lo) + ", " + num(depth.hi) + "] mm (" + num(kChestDepthShare.lo) + "-" +
          num(kChestDepthShare.hi) + " x chestWidth)", p.chestDepth);
    if (!kSpineHeightRange.contains(p.spineHeight)) bad("spineHeight", "in " + kSpineHeightRange.text() + " mm", p.spineHeight);
    const double ageEq = std::clamp(5 + (p.chestWidth - 165) / 8, kAgeRange.lo, kAgeRange.hi);
    d = fromAge(ageEq);
    d.chestWidth = p.chestWidth;
    d.chestDepth = p.chestDepth;
    d.spineHeight = p.spineHeight;
  }
  if (!kRibPairsRange.contains(p.ribPairs)) bad("ribPairs", "in " + kRibPairsRange.text(true), p.ribPairs);
  if (!kHallerIndexRange.contains(p.hallerIndex))
    bad("hallerIndex", "in " + kHallerIndexRange.text() + " (normal ~2.5, pectus excavatum > 3.25)", p.hallerIndex);
  if (!kEdgeLengthRange.contains(p.edgeLength)) bad("edgeLength", "in " + kEdgeLengthRange.text() + " mm", p.edgeLength);
  if (!(p.blend <= 10)) bad("blend", "in [0, 10] mm (negative: automatic)", p.blend);
  if (!(p.funnelWidth >= kFunnelMinSize && p.funnelWidth <= d.chestWidth))
    bad("funnelWidth", "in [" + num(kFunnelMinSize) + ", " + num(d.chestWidth) + "] mm (at most the chest's inner width)", p.funnelWidth,
        "a funnel cannot be wider than the chest");
  if (!(p.funnelHeight >= kFunnelMinSize && p.funnelHeight <= kFunnelHeightShare * d.spineHeight))
    bad("funnelHeight", "in [" + num(kFunnelMinSize) + ", " + num(kFunnelHeightShare * d.spineHeight) + "] mm", p.funnelHeight);
  if (!(std::abs(p.funnelCenterX) <= kFunnelCenterXShare * p.funnelWidth))
    bad("funnelCenterX", "in [" + num(-kFunnelCenterXShare * p.funnelWidth) + ", " + num(kFunnelCenterXShare * p.funnelWidth) + "] mm (" +
        num(kFunnelCenterXShare) + " x funnelWidth, so the funnel still depresses the sternum)",
        p.funnelCenterX);
  if (!kFunnelCenterZRange.contains(p.funnelCenterZ))
    bad("funnelCenterZ", "in " + kFunnelCenterZRange.text() + " (0 jugular notch, 1 xiphisternal junction)", p.funnelCenterZ);
  d.sternumLength = 0;  // set by the model
  return d;
}

namespace {

double resolution(const RibCageParams& p, const Dimensions& dims) { return std::min({0.85 * p.edgeLength, dims.ribThickness / 2.5, 1.8}); }

// the anatomy with the funnel depth calibrated to the requested index (measured on the implicit surface)
CageModel calibratedModel(const RibCageParams& p, RibCageStats& st, const std::function<void(int, const char*)>& prog) {
  const Dimensions dims = validate(p);
  st.hallerRequested = p.hallerIndex;
  const double h = resolution(p, dims);
  const double spacing = std::clamp(2 * h, 0.8, 1.5);
  auto t0 = Clock::now();

  // --- calibrate the funnel depth so that T / AP = requested index (measured on the implicit surface)
  prog(2, "calibrating funnel depth");
  const CageModel rest = buildModel(dims, p, 0.0, spacing);
  const CageField restField(rest);
  const double T = transverse(rest, restField);
  const Ap apRest = apDistance(rest, restField, 1.0);
  const double hRest = T / apRest.ap;
  st.hallerRest = hRest;
  const double apFloor = std::max(0.2 * dims.chestDepth, 10.0);
  const double hMax = std::min(12.0, T / apFloor);
  if (p.hallerIndex < hRest - 1e-9)
    bad("hallerIndex", "in [" + num(hRest) + ", " + num(hMax) + "] for this chest", p.hallerIndex,
        "below the index of the same chest without a funnel; a protruding sternum is not modelled");
  if (p.hallerIndex > hMax)
    bad("hallerIndex", "in [" + num(hRest) + ", " + num(hMax) + "] for this chest", p.hallerIndex,
        "the sternum would come closer than " + num(apFloor) + " mm to the vertebra");
  const double apTarget = T / p.hallerIndex;
  auto apOf = [&](double depth, double dz) {
    const CageModel m = buildModel(dims, p, depth, spacing);
    const CageField f(m);
    return apDistance(m, f, dz).ap;
  };
  double depth = 0;
  if (apTarget < apRest.ap - 1e-6) {
    // Illinois regula falsi on g(depth) = ap(depth) - target (non-increasing in depth)
    double a = 0, ga = apRest.ap - apTarget;
    double b = 1.5 * dims.chestDepth, gb = apOf(b, 1.0) - apTarget;
    if (gb > 0)
      bad("funnelCenterX", "closer to the sternum", p.funnelCenterX, "the funnel cannot depress the sternum enough");
    int side = 0;
    for (int it = 0; it < 40; ++it) {
      const double c = (a * gb - b * ga) / (gb - ga);
      const double gc = apOf(c, 1.0) - apTarget;
      depth = c;
      if (std::abs(gc) < 0.01) break;
      if (gc > 0) { a = c; ga = gc; if (side == 1) gb *= 0.5; side = 1; }
      else { b = c; gb = gc; if (side == -1) ga *= 0.5; side = -1; }
    }
  }
  const CageModel model = buildModel(dims, p, depth, spacing);
  const CageField field(model);
  double xin[2];
  st.transverseInner = transverse(model, field, xin);
  const Ap apFinal = apDistance(model, field, 0.5);
  st.apMin = apFinal.ap;
  st.zDeepest = apFinal.z;
  st.hallerModel = st.transverseInner / st.apMin;
  st.funnelDepth = depth;
  st.dims = dims;
  st.dims.sternumLength = model.zNotch - model.zTip;
  st.secondsField = secondsSince(t0);
  return model;
}

// the field's zero set by sparse marching tetrahedra, decimated to the edge length without self-intersections
void extractSurface(const CageModel& model, const CageField& field, const RibCageParams& p, CMeshO& out, RibCageStats& st) {
  const double h = resolution(p, model.d);
  auto t0 = Clock::now();
  SparseGrid g;
  // the grid follows the automatic fillet radius even when an explicit (smaller) one is given, so that
  // cages differing only in the fillet are extracted on the same grid
  const double hg = std::min(h, 0.95 * (1.0 + std::max(model.blend, autoBlend(model.d))) / std::sqrt(3.0));
  g.h = hg;
  g.block = 8;
  const Vec3 lo = field.boxMin() - Vec3::Constant(2 * hg), hi = field.boxMax() + Vec3::Constant(2 * hg);
  g.origin = Vec3(std::floor(lo.x() / hg) * hg, std::floor(lo.y() / hg) * hg, std::floor(lo.z() / hg) * hg);
  for (int a = 0; a < 3; ++a) g.points[std::size_t(a)] = int(std::ceil((hi[a] - g.origin[a]) / hg)) + 2;
  const auto nb = g.blocks();
  g.active.assign(std::size_t(nb[0]) * nb[1] * nb[2], 0);
  const double bl = g.block * hg;
  for (const auto& s : field.segments()) {
    int a0[3], a1[3];
    for (int a = 0; a < 3; ++a) {
      a0[a] = std::max(0, int(std::floor((s.lo[a] - 2 * hg - g.origin[a]) / bl)));
      a1[a] = std::min(nb[std::size_t(a)] - 1, int(std::floor((s.hi[a] + 2 * hg - g.origin[a]) / bl)));
    }
    for (int z = a0[2]; z <= a1[2]; ++z)
      for (int y = a0[1]; y <= a1[1]; ++y)
        for (int x = a0[0]; x <= a1[0]; ++x) g.active[(std::size_t(z) * nb[1] + y) * nb[0] + x] = 1;
  }
  st.gridSpacing = hg;
  TriSoup soup = marchingTets(g, [&](const Vec3& q) { return field(q); });
  st.rawFaces = soup.F.size();
  st.secondsExtract = secondsSince(t0);

  // --- into the CMeshO, decimate to the target edge length
  t0 = Clock::now();
  out.Clear();
  {
    auto vi = vcg::tri::Allocator<CMeshO>::AddVertices(out, soup.V.size());
    for (const auto& v : soup.V) { vi->P() = toPoint(v); ++vi; }
    auto fi = vcg::tri::Allocator<CMeshO>::AddFaces(out, soup.F.size());
    for (const auto& f : soup.F) {
      for (int k = 0; k < 3; ++k) fi->V(k) = &out.vert[std::size_t(f[std::size_t(k)])];
      ++fi;
    }
  }
  double area = 0;
  for (const auto& f : soup.F)
    area += 0.5 * (soup.V[std::size_t(f[1])] - soup.V[std::size_t(f[0])]).cross(soup.V[std::size_t(f[2])] - soup.V[std::size_t(f[0])]).norm();
  soup = TriSoup{};
  st.decimationRetries = decimateEmbedded(out, int(area / (0.433 * p.edgeLength * p.edgeLength)), p.edgeLength);
  st.secondsDecimate += secondsSince(t0);
}

// tissue and part of each face from the primitive nearest to its centroid (only: one tissue for all)
void labelFaces(const CageModel& model, const CageField& field, CMeshO& out, Tissue only = Tissue::Unknown) {
  std::vector<int> tissue(out.face.size()), part(out.face.size());
#pragma omp parallel for schedule(static)
  for (long long i = 0; i < (long long)out.face.size(); ++i) {
    const auto& f = out.face[std::size_t(i)];
    const Vec3 c = (toEigen(f.cP(0)) + toEigen(f.cP(1)) + toEigen(f.cP(2))) / 3.0;
    const auto [ci, u] = field.nearest(c);
    const Curve& cv = model.curves[std::size_t(ci)];
    if (cv.rib == 0) {
      tissue[std::size_t(i)] = int(Tissue::Sternum);
      part[std::size_t(i)] = u < cv.sternumSplit[0] ? kManubrium : (u < cv.sternumSplit[1] ? kSternumBody : kXiphoid);
    } else {
      tissue[std::size_t(i)] = int(u >= cv.uCartilage ? Tissue::Cartilage : Tissue::Bone);
      part[std::size_t(i)] = ribPart(cv.side, cv.rib);
    }
  }
  if (only != Tissue::Unknown) std::fill(tissue.begin(), tissue.end(), int(only));
  writeFaceLabels(out, tissue, part);
  vcg::tri::UpdateBounding<CMeshO>::Box(out);
}

std::vector<Landmark> landmarks(const CageModel& model, const CageField& field, const RibCageStats& st) {
  const Dimensions& dims = st.dims;
  std::vector<Landmark> lms;
  const Curve& sternum = model.curves.back();
  for (const Curve& c : model.curves)
    if (c.rib > 0) lms.push_back({cvjLandmark(c.side, c.rib), c.c.front()});
  lms.push_back({kSternumLowerEnd, sternum.c.back()});
  {
    double s;
    const double yFront = field.boxMax().y() + 10;
    Vec3 deep(0, sternum.c.front().y(), st.zDeepest);
    if (firstHit(field, Vec3(0, yFront, st.zDeepest), -Vec3::UnitY(), yFront, s)) deep = Vec3(0, yFront - s, st.zDeepest);
    lms.push_back({kFunnelDeepest, deep});
  }
  lms.push_back({kSternumUpperEnd, sternum.c.front()});
  lms.push_back({kVertebraAtDeepest, Vec3(0, 0, st.zDeepest)});
  auto lateral = [&](int side, int rib) {
    for (const Curve& c : model.curves)
      if (c.side == side && c.rib == rib) {
        std::size_t best = 0;
        for (std::size_t i = 0; i < c.c.size(); ++i)
          if (std::abs(c.c[i].x()) > std::abs(c.c[best].x())) best = i;
        return c.c[best];
      }
    return Vec3(0, 0, 0);
  };
  for (int side = 1; side <= 2; ++side)
    for (int s = 4; s <= 5; ++s) lms.push_back({barExitLandmark(side, s), 0.5 * (lateral(side, s) + lateral(side, s + 1))});
  lms.push_back({kDiaphragmDome, Vec3(0, 0.5 * dims.chestDepth, model.zXJ)});
  lms.push_back({kLungApex, Vec3(0, 0.3 * dims.chestDepth, dims.spineHeight)});
  return lms;
}

}  // namespace

std::vector<Landmark> generateRibCage(const RibCageParams& p, CMeshO& out, RibCageStats* stats,
                                      const std::function<void(int, const char*)>& progress) {
  auto prog = [&](int pc, const char* w) { if (progress) progress(pc, w); };
  RibCageStats st;
  const CageModel model = calibratedModel(p, st, prog);
  const CageField field(model);
  prog(15, "extracting the surface");
  extractSurface(model, field, p, out, st);
  prog(85, "labelling");
  const auto t0 = Clock::now();
  labelFaces(model, field, out);
  st.secondsLabel = secondsSince(t0);
  auto lms = landmarks(model, field, st);
  if (stats) *stats = st;
  prog(100, "done");
  return lms;
}

std::vector<Landmark> generateTissueLayers(const RibCageParams& p, std::array<OwnedMesh, 3>& out, RibCageStats* stats,
                                           const std::function<void(int, const char*)>& progress) {
  auto prog = [&](int pc, const char* w) { if (progress) progress(pc, w); };
  RibCageStats st;
  const CageModel model = calibratedModel(p, st, prog);
  const CageField field(model);
  // segment i of a rib spans u[i]..u[i+1]: the one holding the costochondral junction belongs to both
  // tissues and each cut end is capped by a half-ellipsoid, so bone and cartilage overlap by a few mm;
  // the cartilages stop at the sternum's surface (their last kept segment and its cap reach a few mm in)
  const CageField sternumField(model, 5.0, [](const Curve& c, int) { return c.rib == 0; });
  const std::array<std::function<bool(const Curve&, int)>, 3> keep{
      [](const Curve& c, int i) { return c.rib > 0 && c.u[std::size_t(i)] < c.uCartilage; },
      [&](const Curve& c, int i) {
        return c.rib > 0 && c.u[std::size_t(i) + 1] > c.uCartilage && sternumField(c.c[std::size_t(i)]) > 0;
      },
      [](const Curve& c, int) { return c.rib == 0; }};
  const std::array<Tissue, 3> tissues{Tissue::Bone, Tissue::Cartilage, Tissue::Sternum};
  for (std::size_t k = 0; k < 3; ++k) {
    prog(15 + 25 * int(k), tissueName(tissues[k]));
    const CageField part(model, 5.0, keep[k]);
    extractSurface(model, part, p, out[k], st);
    labelFaces(model, field, out[k], tissues[k]);
  }
  auto lms = landmarks(model, field, st);
  if (stats) *stats = st;
  prog(100, "done");
  return lms;
}

CageModel buildCalibratedModel(const RibCageParams& p, RibCageStats* stats, std::vector<Landmark>* lms) {
  RibCageStats st;
  CageModel model = calibratedModel(p, st, [](int, const char*) {});
  if (lms) {
    const CageField field(model);
    *lms = landmarks(model, field, st);
  }
  if (stats) *stats = st;
  return model;
}

namespace {
// arc length of a curve's centre line between parameters u0 and u1, over the samples with |x| >= xMin
double arcLength(const Curve& c, double u0, double u1, double xMin) {
  double len = 0;
  for (std::size_t i = 1; i < c.c.size(); ++i)
    if (c.u[i - 1] >= u0 && c.u[i] <= u1 && std::abs(c.c[i].x()) >= xMin && std::abs(c.c[i - 1].x()) >= xMin)
      len += (c.c[i] - c.c[i - 1]).norm();
  return len;
}
}  // namespace

Anatomy measureAnatomy(const RibCageParams& p) {
  Anatomy a;
  a.dims = validate(p);
  const CageModel rest = buildModel(a.dims, p, 0.0, 1.0);
  const CageField field(rest);
  a.restIndex = transverse(rest, field) / apDistance(rest, field, 1.0).ap;
  a.sternumLength = rest.zNotch - rest.zTip;
  a.cartilage = cartilageDiameters(a.dims, p.cartilageSection);
  a.sternumHalfWidth = 0.5 * a.dims.sternumWidth;
  for (const Curve& c : rest.curves) {
    if (c.side != 1 || c.rib < 1 || c.rib > 7) continue;
    std::size_t lateral = 0;  // where the anterior rib begins
    for (std::size_t i = 0; i < c.c.size(); ++i)
      if (std::abs(c.c[i].x()) > std::abs(c.c[lateral].x())) lateral = i;
    Anatomy::Rib& r = a.ribs[std::size_t(c.rib - 1)];
    r.length = arcLength(c, 0, 1, a.sternumHalfWidth);
    r.cartilage = arcLength(c, c.uCartilage, 1, a.sternumHalfWidth);
    r.anteriorShare = r.cartilage / arcLength(c, c.u[lateral], 1, a.sternumHalfWidth);
    if (c.rib == 5)
      for (std::size_t i = 1; i < c.c.size(); ++i)
        if (c.u[i - 1] < c.uCartilage && c.u[i] >= c.uCartilage) a.fifthJunction = std::abs(c.c[i].x());
  }
  return a;
}

}  // namespace pectus::ribcage
