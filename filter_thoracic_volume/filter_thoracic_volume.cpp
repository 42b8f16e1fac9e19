#include "filter_thoracic_volume.h"

#include <vcg/complex/algorithms/update/bounding.h>
#include <vcg/complex/algorithms/update/normal.h>

#include <chrono>

#include "pectus/errors.h"
#include "pectus/labels.h"
#include "pectus/vol/thoracic_volume.h"

using pectus::InputError;
using pectus::ml::FilterContext;
using pectus::ml::fmt;
using pectus::ml::defaultLandmarkLayer;
namespace vol = pectus::vol;
using pectus::ml::addFloat;
using pectus::ml::addInt;

namespace {
/// a height along z (mm): the given range of the volume filters, the search range of the pectus index
constexpr pectus::ParamRange kHeightRange{-1e6, 1e6};
}  // namespace

namespace {

QStringList rangeSources() { return QStringList() << "Landmarks" << "Given heights"; }
QStringList lowerLimits() {
  return QStringList() << "700 dome of the diaphragm" << "500 lower end of the sternum";
}

void addCommon(const MeshDocument& md, RichParameterList& par, int lowerDefault) {
  par.addParam(RichBool("compare", false, "Compare with a before layer",
                        "Also measure the 'Before layer' and log the change (current minus before) in cm3 and %."));
  par.addParam(pectus::ml::richMesh("beforeLayer", pectus::ml::currentMesh(md), md, "Before layer",
                        "The before state (same mesh and frame as the current layer), when comparing."));
  par.addParam(RichEnum("rangeSource", 0, rangeSources(), "Range from",
                        "Landmarks: heights from landmarks 700/500 and 701. Given heights: 'Lower/Upper height' below."));
  par.addParam(pectus::ml::richMesh("landmarkLayer", defaultLandmarkLayer(md), md, "Landmark layer",
                        "Landmark point layer (vertex quality = code); used when the range comes from landmarks."));
  par.addParam(RichEnum("lowerLimit", lowerDefault, lowerLimits(), "Lower limit landmark",
                        "Lower end from landmarks: 700 diaphragm dome (thesis 6.3.1) or 500 lower sternum end (6.3.2)."));
  addFloat(par, "zLow", 0.0f, "Lower height (mm)",
           "Lower end of the range along z; used with Range from = Given heights.", kHeightRange);
  addFloat(par, "zHigh", 200.0f, "Upper height (mm)",
           "Upper end of the range along z; used with Range from = Given heights.", kHeightRange);
}

struct Common {
  MeshModel* measured = nullptr;
  MeshModel* before = nullptr;
  vol::Soup soup, beforeSoup;
  vol::Range range;
  std::vector<pectus::Landmark> landmarks;
};

std::string lab(const MeshModel& m) { return m.label().toStdString(); }

/// The landmark layer of the cage the range is taken on: the before layer when there is one (both are measured over
/// its range), else the measured layer; by role (FilterContext::landmarkLayer), with the codes `needed`.
MeshModel& landmarkLayerOf(FilterContext& ctx, const MeshModel& measured, const MeshModel* before, std::vector<int> needed,
                           const char* otherwise) {
  const MeshModel& cage = before ? *before : measured;
  return ctx.landmarkLayer("landmarkLayer", {&cage}, needed,
                           std::string("Pick the point layer of landmarks written with the cage (vertex quality = landmark code, "
                                       "e.g. 'ribcage landmarks'), or set ") + otherwise + ".",
                           {&measured, before});
}

/// The before layer when 'Compare' is on (by role: FilterContext::beforeLayer), else nullptr.
MeshModel* beforeLayerOf(FilterContext& ctx, const MeshModel& measured) {
  return ctx.boolean("compare") ? &ctx.beforeLayer("beforeLayer", measured) : nullptr;
}

double needLandmark(const std::vector<pectus::Landmark>& lms, int code, const std::string& layer, const char* what) {
  auto p = pectus::findLandmark(lms, code);
  if (!p)
    throw InputError("landmark " + std::to_string(code) + " (" + what + ") is not in the landmark layer '" + layer +
                     "': choose the landmark layer (vertex quality = landmark code) or set 'Range from' to Given "
                     "heights");
  return p->z();
}

Common readCommon(FilterContext& ctx, bool needRange = true) {
  Common c;
  c.measured = &ctx.current();
  c.soup = vol::soupFromMesh(c.measured->cm, lab(*c.measured));
  if (c.soup.F.empty())
    throw InputError("layer '" + lab(*c.measured) + "' has no faces: the measured layer must be the rib cage surface");
  c.before = beforeLayerOf(ctx, *c.measured);
  if (c.before) {
    c.beforeSoup = vol::soupFromMesh(c.before->cm, lab(*c.before));
    vol::requireComparablePair(c.beforeSoup, c.soup, lab(*c.before), lab(*c.measured));
  }
  const int src = ctx.enumIn("rangeSource", 2);
  const int lower = ctx.enumIn("lowerLimit", 2);
  if (src == 0 || !needRange) {
    const std::vector<int> needed = src == 0 ? std::vector<int>{lower == 0 ? pectus::kDiaphragmDome : pectus::kSternumLowerEnd,
                                                                pectus::kLungApex}
                                             : std::vector<int>{};
    MeshModel& lm = landmarkLayerOf(ctx, *c.measured, c.before, needed, "'Range from' to Given heights");
    c.landmarks = pectus::readLandmarks(lm.cm);
    if (src == 0) {
      c.range.zLo = lower == 0 ? needLandmark(c.landmarks, pectus::kDiaphragmDome, lab(lm), "dome of the diaphragm")
                               : needLandmark(c.landmarks, pectus::kSternumLowerEnd, lab(lm), "lower end of the sternum");
      c.range.zHi = needLandmark(c.landmarks, pectus::kLungApex, lab(lm), "lung apex");
    }
  }
  if (src == 1) {
    c.range.zLo = ctx.floatIn("zLow");
    c.range.zHi = ctx.floatIn("zHigh");
  }
  if (needRange) vol::requireRange(c.range, "z = " + fmt(c.range.zLo, 2) + " .. " + fmt(c.range.zHi, 2) + " mm");
  return c;
}

std::string cm3(double mm3) { return fmt(mm3 / 1000.0, 3) + " cm3"; }

/// the Log line of a before/after change, and its values volume_change_cm3 and volume_change_pct
void logChange(FilterContext& ctx, const std::string& what, double before, double after) {
  const double d = after - before;
  ctx.results().set("volume_change_cm3", d / 1000.0);
  ctx.results().set("volume_change_pct", 100.0 * d / before);
  ctx.log(what + " change: " + (d >= 0 ? "+" : "") + cm3(d) + " (" + (d >= 0 ? "+" : "") + fmt(100.0 * d / before, 2) +
          " %), before " + cm3(before) + ", after " + cm3(after));
}

double seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void addSoupLayer(FilterContext& ctx, const QString& label, const vol::Soup& s) {
  MeshModel& mm = ctx.addLayer(label, false);  // the measured layer stays current (chains of measurements)
  CMeshO& m = ctx.modify(mm);
  auto vi = vcg::tri::Allocator<CMeshO>::AddVertices(m, s.V.size());
  for (const auto& p : s.V) (vi++)->P() = pectus::toPoint(p);
  auto fi = vcg::tri::Allocator<CMeshO>::AddFaces(m, s.F.size());
  for (const auto& f : s.F) {
    for (int k = 0; k < 3; ++k) fi->V(k) = &m.vert[f[k]];
    ++fi;
  }
  pectus::ml::updateBoxAndNormals(mm);
}

}  // namespace

FilterThoracicVolumePlugin::FilterThoracicVolumePlugin() {
  pectus::ml::FilterSpec s;
  s.id = FP_SLICE_VOLUME;
  s.name = "Pectus: Thoracic Volume (Slice Method)";
  s.pythonName = "compute_thoracic_volume_slice";
  s.info =
      "Thoracic volume of the rib cage by parallel slices (thesis 6.3.1); with a 'before' layer, also the "
      "change after the repair.";
  s.doc = "thoracic_volume_slice";
  s.advanced = QStringList{"spacing", "resolution", "rays"};
  s.cls = pectus::ml::HostFilter::Measure;
  addFilter(this, s);

  s.id = FP_ENVELOPE_VOLUME;
  s.name = "Pectus: Thoracic Volume (Ferguson Envelope)";
  s.pythonName = "compute_thoracic_volume_envelope";
  s.info =
      "Thoracic volume inside C1 Ferguson patches shrunk onto the rib cage (thesis 6.3.2); with a 'before' "
      "layer, also the change.";
  s.doc = "thoracic_volume_envelope";
  s.advanced = QStringList{"patchesLong", "patchesAround", "initialStep", "minStep", "smoothing",
                            "tessellation"};
  s.cls = pectus::ml::HostFilter::Measure;
  addFilter(this, s);

  s.id = FP_PECTUS_INDEX;
  s.name = "Pectus: Pectus Index";
  s.pythonName = "compute_pectus_index";
  s.info =
      "Haller and correction indices on the slice at the deepest point of the funnel; with a 'before' "
      "layer, before and after.";
  s.doc = "pectus_index";
  s.advanced = QStringList{"rays"};
  s.cls = pectus::ml::HostFilter::Measure;
  addFilter(this, s);
}

void FilterThoracicVolumePlugin::initParameters(int id, const MeshDocument& md, RichParameterList& par) {
  if (id == FP_SLICE_VOLUME) {
    addCommon(md, par, 0);
    addFloat(par, "spacing", 2.6f, "Spacing (mm)",
             "Distance between cutting planes (thesis ~2.6 mm); adjusted to fit the range.", vol::kSpacingRange);
    addInt(par, "resolution", 512, "Resolution (pixels)",
           "Pixels along the longer side of the slices' common raster (thesis: 512 x 512).", vol::kResolutionRange);
    addInt(par, "rays", 720, "Rays",
           "Rays from the slice centroid that find the inner wall; more follow it closer.", vol::kRaysRange);
  } else if (id == FP_ENVELOPE_VOLUME) {
    addCommon(md, par, 1);
    addInt(par, "patchesLong", 16, "Patches along z (n)",
           "Ferguson patches along the long axis (thesis 16); denser ones fall into rib gaps.", vol::kPatchesLongRange);
    addInt(par, "patchesAround", 16, "Patches around (m)",
           "Number of Ferguson patches around the axis (thesis 16).", vol::kPatchesAroundRange);
    addFloat(par, "initialStep", 0.0f, "Initial step (mm)",
             "First radial step of the key points; 0 = a quarter of the start radius.", {0, 1e5});
    addFloat(par, "minStep", 0.05f, "Final step (mm)",
             "Stop once the halved step is below this: the envelope's accuracy in mm.", vol::kMinStepRange);
    par.addParam(RichBool("smoothing", true, "Smoothing (eq. 6-1)",
                          "Eq. 6-1: raise key points to their z-neighbours' mean radius, to bridge intercostal gaps."));
    addInt(par, "tessellation", 8, "Output samples per patch",
           "Samples per patch side of the envelope layer (the volume uses the patches).", {1, 64});
  } else if (id == FP_PECTUS_INDEX) {
    par.addParam(RichBool("compare", false, "Compare with a before layer",
                          "Also measure the 'Before layer' and log both indices side by side."));
    par.addParam(pectus::ml::richMesh("beforeLayer", pectus::ml::currentMesh(md), md, "Before layer",
                          "The before state (same mesh, same frame) when 'Compare with a before layer' is on."));
    par.addParam(RichEnum("levelSource", 0, QStringList() << "Landmarks 501/503" << "Automatic (deepest slice)",
                          "Level from",
                          "Landmarks: the slice at landmark 501, vertebra 503. Automatic: deepest slice between the heights."));
    par.addParam(pectus::ml::richMesh("landmarkLayer", defaultLandmarkLayer(md), md, "Landmark layer",
                          "Landmark point layer (vertex quality = code); by default the layer whose name ends in 'landmarks'."));
    addFloat(par, "zLow", 0.0f, "Lower height (mm)",
             "Automatic level: lower end of the search along z.", kHeightRange);
    addFloat(par, "zHigh", 200.0f, "Upper height (mm)",
             "Automatic level: upper end of the search along z.", kHeightRange);
    addInt(par, "rays", 720, "Rays",
           "Rays from the slice centroid that find the inner boundary.", vol::kRaysRange);
  }
}

void FilterThoracicVolumePlugin::run(int id, FilterContext& ctx) {
  switch (id) {
    case FP_SLICE_VOLUME: runSlice(ctx); break;
    case FP_ENVELOPE_VOLUME: runEnvelope(ctx); break;
    case FP_PECTUS_INDEX: runIndex(ctx); break;
    default: throw std::logic_error("unknown filter id");
  }
}

namespace {
/// refuses a layer that does not surround the range (a single triangle, a patch beside the range): no
/// volume, or more than half of the slices empty; from the slice result of that layer, or a coarse slice
/// probe for the envelope
void requireEnclosure(const vol::SliceResult& r, const std::string& layer, const vol::Range& range) {
  if (r.volume > 0 && 2 * r.emptySlices <= r.slices) return;
  throw InputError("layer '" + layer + "' does not surround the range z = " + fmt(range.zLo, 2) + " to " +
                   fmt(range.zHi, 2) + " mm: " + std::to_string(r.emptySlices) + " of " + std::to_string(r.slices) +
                   " slices enclose no area; check the heights or the layer");
}
}  // namespace

void FilterThoracicVolumePlugin::runSlice(FilterContext& ctx) {
  vol::SliceParams p;
  p.spacing = ctx.floatIn("spacing");
  p.resolution = ctx.intIn("resolution");
  p.rays = ctx.intIn("rays");
  Common c = readCommon(ctx);
  auto measure = [&](const vol::Soup& s, MeshModel& mm, int p0, int p1) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto r = vol::sliceVolume(s, c.range, p, [&](int pc, const char* w) { ctx.progress(p0 + (p1 - p0) * pc / 100, w); });
    ctx.log("Slice method, layer '" + lab(mm) + "': intrathoracic volume " + cm3(r.volume) + " (" +
            std::to_string(r.slices) + " slices of " + fmt(r.spacingUsed, 3) + " mm from z = " + fmt(c.range.zLo, 2) +
            " to " + fmt(c.range.zHi, 2) + " mm, pixel " + fmt(r.pixel, 3) + " mm, polygon volume " +
            cm3(r.polygonVolume) + ", empty slices " + std::to_string(r.emptySlices) + ": " +
            std::to_string(r.bridgedSlices) + " bridged, " + std::to_string(r.endEmptySlices) +
            " at the ends counted as zero, min ray coverage " +
            fmt(100 * r.minCoverage, 1) + " %, " + fmt(seconds(t0), 3) + " s)");
    requireEnclosure(r, lab(mm), c.range);
    // the measured layer's figures; the before layer's with the prefix before_
    const std::string k = &mm == c.before ? "before_" : "";
    auto& res = ctx.results();
    res.set(k + "volume_cm3", r.volume / 1000.0);
    res.set(k + "slices", r.slices);
    res.set(k + "spacing_mm", r.spacingUsed);
    res.set(k + "pixel_mm", r.pixel);
    res.set(k + "polygon_volume_cm3", r.polygonVolume / 1000.0);
    res.set(k + "empty_slices", r.emptySlices);
    res.set(k + "bridged_slices", r.bridgedSlices);
    res.set(k + "end_empty_slices", r.endEmptySlices);
    res.set(k + "min_ray_coverage_pct", 100 * r.minCoverage);
    res.set(k + "seconds", seconds(t0));
    res.set("z_low_mm", c.range.zLo);
    res.set("z_high_mm", c.range.zHi);
    return r.volume;
  };
  if (c.before) {
    const double vb = measure(c.beforeSoup, *c.before, 0, 50), va = measure(c.soup, *c.measured, 50, 100);
    logChange(ctx, "Slice method intrathoracic volume", vb, va);
  } else {
    measure(c.soup, *c.measured, 0, 100);
  }
}

void FilterThoracicVolumePlugin::runEnvelope(FilterContext& ctx) {
  vol::EnvelopeParams p;
  p.nLong = ctx.intIn("patchesLong");
  p.mAround = ctx.intIn("patchesAround");
  p.initialStep = ctx.floatIn("initialStep");
  p.minStep = ctx.floatIn("minStep");
  p.smoothing = ctx.boolean("smoothing");
  p.tessellation = ctx.intIn("tessellation");
  Common c = readCommon(ctx);
  if (auto e = pectus::findLandmark(c.landmarks, pectus::kSternumLowerEnd)) p.sternumEnd = *e;
  struct Out {
    vol::Soup mesh;
    QString label;
  };
  std::vector<Out> outs;
  auto measure = [&](const vol::Soup& s, MeshModel& mm, int p0, int p1) {
    vol::SliceParams probe;  // coarse: only whether the layer surrounds the range at all
    probe.spacing = std::max(vol::kSpacingRange.lo, (c.range.zHi - c.range.zLo) / 8);
    probe.resolution = 64;
    probe.rays = 64;
    requireEnclosure(vol::sliceVolume(s, c.range, probe), lab(mm), c.range);
    const auto t0 = std::chrono::steady_clock::now();
    const auto r = vol::fergusonEnvelope(s, c.range, p, [&](int pc, const char* w) { ctx.progress(p0 + (p1 - p0) * pc / 100, w); });
    const double dt = seconds(t0);
    Out o{r.env.tessellate(p.tessellation), QString::fromStdString(lab(mm) + " envelope")};
    for (auto& v : o.mesh.V) v = pectus::toEigen(pectus::toPoint(v));  // the layer's float coordinates
    const double meshVol = vol::divergenceVolume(o.mesh);
    ctx.log("Ferguson envelope, layer '" + lab(mm) + "': thoracic volume " + cm3(r.volume) + " (" +
            std::to_string(p.nLong) + " x " + std::to_string(p.mAround) + " patches, z = " + fmt(c.range.zLo, 2) +
            " to " + fmt(c.range.zHi, 2) + " mm, " + std::to_string(r.touching) + " key points touching, " +
            std::to_string(r.singular) + " singular, " + std::to_string(r.levels) + " step levels, " +
            std::to_string(r.samples) + " samples, " + fmt(dt, 3) + " s)");
    ctx.log("Envelope layer '" + o.label.toStdString() + "' (" + std::to_string(o.mesh.F.size()) +
            " triangles, closed): mesh volume " + fmt(meshVol, 6) + " mm3");
    const std::string k = &mm == c.before ? "before_" : "";
    auto& res = ctx.results();
    res.set(k + "volume_cm3", r.volume / 1000.0);
    res.set(k + "key_points_touching", r.touching);
    res.set(k + "key_points_singular", r.singular);
    res.set(k + "step_levels", r.levels);
    res.set(k + "samples", r.samples);
    res.set(k + "seconds", dt);
    res.set(k + "envelope_triangles", o.mesh.F.size());
    res.set(k + "envelope_mesh_volume_mm3", meshVol);
    res.set("z_low_mm", c.range.zLo);
    res.set("z_high_mm", c.range.zHi);
    outs.push_back(std::move(o));
    return r.volume;
  };
  if (c.before) {
    const double vb = measure(c.beforeSoup, *c.before, 0, 50), va = measure(c.soup, *c.measured, 50, 100);
    logChange(ctx, "Ferguson envelope thoracic volume", vb, va);
  } else {
    measure(c.soup, *c.measured, 0, 100);
  }
  // a closed measured layer: its own divergence volume (compare with Compute Geometric Measures)
  for (MeshModel* mm : {c.before, c.measured}) {
    if (!mm) continue;
    const auto& s = mm == c.measured ? c.soup : c.beforeSoup;
    const pectus::Topology topo(s);
    const bool closed =
        topo.badFace < 0 &&
        std::none_of(s.F.begin(), s.F.end(), [](const auto& f) { return f[0] == f[1] || f[1] == f[2] || f[2] == f[0]; }) &&
        std::all_of(topo.edges.begin(), topo.edges.end(), [](const pectus::Topology::Edge& e) { return e.faces == 2; });
    if (closed) {
      const double v = vol::divergenceVolume(s);
      ctx.log("Layer '" + lab(*mm) + "' is closed: divergence volume " + fmt(v, 6) + " mm3");
      ctx.results().set(std::string(mm == c.before ? "before_" : "") + "layer_divergence_volume_mm3", v);
    }
  }
  for (const auto& o : outs) addSoupLayer(ctx, o.label, o.mesh);
}

void FilterThoracicVolumePlugin::runIndex(FilterContext& ctx) {
  MeshModel& cur = ctx.current();
  vol::Soup soup = vol::soupFromMesh(cur.cm, lab(cur));
  if (soup.F.empty()) throw InputError("layer '" + lab(cur) + "' has no faces: the measured layer must be the rib cage");
  MeshModel* before = beforeLayerOf(ctx, cur);
  vol::Soup beforeSoup;
  if (before) {
    beforeSoup = vol::soupFromMesh(before->cm, lab(*before));
    vol::requireComparablePair(beforeSoup, soup, lab(*before), lab(cur));
  }
  vol::IndexInputs in;
  in.rays = ctx.intIn("rays");
  const int src = ctx.enumIn("levelSource", 2);
  if (src == 0) {
    MeshModel& lm = landmarkLayerOf(ctx, cur, before, {pectus::kFunnelDeepest}, "'Level from' to Automatic");
    const auto lms = pectus::readLandmarks(lm.cm);
    auto deep = pectus::findLandmark(lms, pectus::kFunnelDeepest);
    if (!deep)
      throw InputError("landmark 501 (deepest point of the funnel) is not in the landmark layer '" + lab(lm) +
                       "': choose the landmark layer or set 'Level from' to Automatic");
    in.level = deep->z();
    in.midlineX = deep->x();
    if (auto v = pectus::findLandmark(lms, pectus::kVertebraAtDeepest)) in.spineY = v->y();
  } else {
    in.searchRange = {ctx.floatIn("zLow"), ctx.floatIn("zHigh")};
  }
  auto measure = [&](const vol::Soup& s, MeshModel& mm) {
    const auto r = vol::pectusIndex(s, in);
    ctx.log("Pectus index, layer '" + lab(mm) + "' at z = " + fmt(r.z, 2) + " mm: Haller index " + fmt(r.haller, 3) +
            ", correction index " + fmt(r.correction, 2) + " % (inner transverse diameter " + fmt(r.transverse, 2) +
            " mm, sternum-vertebra " + fmt(r.apMin, 2) + " mm, chest wall-vertebra " + fmt(r.apMax, 2) + " mm)");
    const std::string k = &mm == before ? "before_" : "";
    auto& res = ctx.results();
    res.set(k + "haller_index", r.haller);
    res.set(k + "correction_index_pct", r.correction);
    res.set(k + "level_z_mm", r.z);
    res.set(k + "transverse_mm", r.transverse);
    res.set(k + "sternum_vertebra_mm", r.apMin);
    res.set(k + "chest_wall_vertebra_mm", r.apMax);
    return r;
  };
  ctx.progress(10, "pectus index");
  if (before) {
    const auto b = measure(beforeSoup, *before);
    ctx.progress(50, "pectus index");
    const auto a = measure(soup, cur);
    ctx.log("Pectus index change: Haller " + fmt(b.haller, 3) + " -> " + fmt(a.haller, 3) + ", correction index " +
            fmt(b.correction, 2) + " % -> " + fmt(a.correction, 2) + " %");
  } else {
    measure(soup, cur);
  }
}

MESHLAB_PLUGIN_NAME_EXPORTER(FilterThoracicVolumePlugin)
