#include "pectus/nuss/bar_planner.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <sstream>

#include "pectus/nuss/nuss_output.h"
#include "pectus/errors.h"
#include "pectus/format.h"

namespace pectus::nuss {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

Eigen::Vector3d needLandmark(const std::vector<Landmark>& lms, int code, const char* what) {
  auto p = findLandmark(lms, code);
  if (!p)
    throw InputError("Landmark " + std::to_string(code) + " (" + what +
                     ") is not in the landmark layer: the planner measures the thoracic volumes and the pectus index with it.");
  return *p;
}

std::string csvField(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}
}  // namespace

std::vector<int> parseLevels(const std::string& text) {
  std::string t = text;
  for (char& c : t)
    if (c == ',' || c == ';') c = ' ';
  std::istringstream in(t);
  std::vector<int> out;
  std::string tok;
  auto bad = [&](const std::string& why) {
    return InputError("Bar levels '" + text + "': " + why +
                      ". Give intercostal spaces (1 = between ribs 1 and 2) as a list like '3,4,5' or a range like '3-5'.");
  };
  while (in >> tok) {
    int a = 0, b = 0;
    char dash = 0, extra = 0;
    std::istringstream one(tok);
    if (tok.find('-', 1) != std::string::npos) {
      if (!(one >> a >> dash >> b) || dash != '-' || (one >> extra)) throw bad("'" + tok + "' is not a range of whole numbers");
    } else {
      if (!(one >> a) || (one >> extra)) throw bad("'" + tok + "' is not a whole number");
      b = a;
    }
    if (a < 1 || b < 1) throw bad("spaces start at 1");
    if (b < a || b - a > 20) throw bad("'" + tok + "' is not an ascending range");
    for (int s = a; s <= b; ++s)
      if (std::find(out.begin(), out.end(), s) == out.end()) out.push_back(s);
  }
  if (out.empty()) throw bad("no level given");
  return out;
}

namespace {
// the cage surface the volumes and the index measure, before or (with an analysis) after: the FE surface
// nodes (0..nv-1) moved by their displacements, without a vertebral column kept as the support (labels.h,
// kVertebralColumn), as the thoracic volume filters leave it out. The layer of the best option is the
// analysed mesh moved by the same displacements (nuss_output.h, deformedSurface).
vol::Soup measuredSurface(const CageSurface& cage, const Analysis* after = nullptr) {
  vol::Soup s;
  s.V = cage.surface.V;
  if (after)
    for (size_t i = 0; i < s.V.size(); ++i) s.V[i] += after->result.displacement(static_cast<int>(i));
  for (size_t f = 0; f < cage.surface.F.size(); ++f)
    if (cage.facePart[f] != kVertebralColumn) s.F.push_back(cage.surface.F[f]);
  return s;
}
}  // namespace

namespace {

void report(const PlanOptions& opt, int pc, const std::string& what) {
  if (opt.progress) opt.progress(pc, what);
}

// the planner's own options: a target to calibrate to, levels, and a configuration of one or two bars
void checkPlanOptions(const PlanOptions& opt) {
  validate(opt.analysis);
  if (!(opt.analysis.targetElevation > 0) && !opt.analysis.targetFromChestLine)
    throw InputError("The bar planner calibrates every option to the sternal elevation: give a positive target elevation (mm), "
                     "or take it from the chest line.");
  if (opt.levels.empty()) throw InputError("No bar level given: list the intercostal spaces to compare, e.g. '3,4,5'.");
  if (!opt.oneBar && !opt.twoBars) throw InputError("Neither one bar nor two bars asked for: choose at least one configuration.");
  if (opt.twoBars && !kSecondOffsetRange.contains(opt.secondOffset))
    throw InputError("The second bar's offset must lie in " + kSecondOffsetRange.text(true) + " intercostal spaces.");
  if (opt.twoBars && opt.secondOffset == 0) throw InputError("The second bar's offset must not be 0: it would share the first bar's space.");
}

struct BarOption { int level, second; };  // the first bar's intercostal space, the second's (0: none)

// the options, each placement checked before any solve
std::vector<BarOption> barOptions(const CageSurface& cage, const std::vector<Landmark>& lms, const PlanOptions& opt) {
  std::vector<BarOption> options;
  for (int s : opt.levels) {
    if (s < 1) throw InputError("Bar level " + std::to_string(s) + ": intercostal spaces start at 1 (between ribs 1 and 2).");
    if (opt.oneBar) options.push_back({s, 0});
    if (!opt.twoBars) continue;
    if (s + opt.secondOffset < 1)
      throw InputError("The second bar of level " + std::to_string(s) + " would go into intercostal space " +
                       std::to_string(s + opt.secondOffset) + ", which does not exist: choose another offset or level.");
    options.push_back({s, s + opt.secondOffset});
  }
  for (const auto& o : options) {
    Placement pl = opt.analysis.place;
    pl.intercostalSpace = o.level;
    pl.secondSpace = o.second;
    pl.secondShare = opt.secondShare;
    checkPlacement(cage, lms, pl);
  }
  return options;
}

// what is measured before and after each option: the slice and envelope volumes' ranges, the envelope, the index
struct Measures {
  vol::Range sliceRange, envelopeRange;
  vol::EnvelopeParams envelope;
  vol::IndexInputs index;
};

Measures measuresOf(const std::vector<Landmark>& lms, const PlanOptions& opt) {
  const double dome = needLandmark(lms, kDiaphragmDome, "dome of the diaphragm").z();
  const double apex = needLandmark(lms, kLungApex, "lung apex").z();
  const Eigen::Vector3d sternumEnd = needLandmark(lms, kSternumLowerEnd, "lower end of the sternum");
  const Eigen::Vector3d deepest = needLandmark(lms, kFunnelDeepest, "deepest point of the funnel");
  Measures m{{dome, apex}, {sternumEnd.z(), apex}, opt.envelope, {}};
  vol::requireRange(m.sliceRange, "landmarks 700 .. 701");
  vol::requireRange(m.envelopeRange, "landmarks 500 .. 701");
  m.envelope.sternumEnd = sternumEnd;
  m.index.level = deepest.z();
  m.index.midlineX = deepest.x();
  if (auto v = findLandmark(lms, kVertebraAtDeepest)) m.index.spineY = v->y();
  m.index.rays = opt.indexRays;
  return m;
}

// the volumes and the pectus index of the cage before the bars
void measureBefore(const CageSurface& cage, const Measures& m, const PlanOptions& opt, Plan& plan) {
  report(opt, 1, "Volumes and pectus index before");
  const vol::Soup before = measuredSurface(cage);
  plan.sliceBefore = vol::sliceVolume(before, m.sliceRange, opt.slice).volume;
  plan.envelopeBefore = vol::fergusonEnvelope(before, m.envelopeRange, m.envelope).volume;
  plan.hallerBefore = vol::pectusIndex(before, m.index).haller;
}

// option k of n analysed (calibrated to the target) on the model, and measured after: its row, its analysis in `a`
PlanRow analyseOption(const CageSurface& cage, const Model& model, const std::vector<Landmark>& lms, const PlanOptions& opt,
                      const Measures& m, const Plan& plan, const BarOption& o, int k, int n, Analysis& a) {
  const auto t0 = Clock::now();
  PlanRow r;
  r.bars = o.second ? 2 : 1;
  r.level = o.level;
  r.secondLevel = o.second;
  r.option = o.second ? "2 bars, spaces " + std::to_string(o.level) + " + " + std::to_string(o.second)
                      : "1 bar, space " + std::to_string(o.level);
  Options ao = opt.analysis;
  ao.place.intercostalSpace = o.level;
  ao.place.secondSpace = o.second;
  ao.place.secondShare = opt.secondShare;
  const int p0 = 5 + 90 * k / n, p1 = 5 + 90 * (k + 1) / n;
  ao.progress = [&](int pc, const std::string& w) { report(opt, p0 + (p1 - p0) * pc / 125, r.option + ": " + w); };
  a = analyze(cage, model, lms, ao);
  r.force = a.force;
  r.elevation = a.elevation;
  r.solves = a.calibration ? a.calibration->evaluations : 1;
  r.maxStress = a.maxStressBody;  // the singular peaks at the tissue junctions would rank the mesh, not the bar
  r.maxStrain = a.maxStrain;
  r.maxStressAt = a.maxStressBodyAt.describe();
  r.maxStrainAt = a.maxStrainAt.describe();
  r.maxStressWhere = a.maxStressBodyAt.where();
  r.maxStrainWhere = a.maxStrainAt.where();

  report(opt, p0 + (p1 - p0) * 4 / 5, r.option + ": volumes and pectus index after");
  const vol::Soup after = measuredSurface(cage, &a);
  const double sv = vol::sliceVolume(after, m.sliceRange, opt.slice).volume;
  const double ev = vol::fergusonEnvelope(after, m.envelopeRange, m.envelope).volume;
  r.sliceGain = sv - plan.sliceBefore;
  r.slicePercent = 100.0 * r.sliceGain / plan.sliceBefore;
  r.envelopeGain = ev - plan.envelopeBefore;
  r.envelopePercent = 100.0 * r.envelopeGain / plan.envelopeBefore;
  r.hallerAfter = vol::pectusIndex(after, m.index).haller;
  r.seconds = since(t0);
  return r;
}

// the row joins the plan; its analysis is kept when it is the best so far (lowest force or lowest stress)
void addRow(const PlanOptions& opt, PlanRow r, Analysis& a, Plan& plan) {
  const auto key = [&](const PlanRow& x) { return opt.best == PlanOptions::Best::LowestForce ? x.force : x.maxStress; };
  if (plan.best < 0 || key(r) < key(plan.rows[plan.best])) {
    plan.best = static_cast<int>(plan.rows.size());
    plan.bestAnalysis = std::move(a);
  }
  plan.rows.push_back(std::move(r));
}

}  // namespace

Plan planBars(const CageSurface& cage, const std::vector<Landmark>& lms, const PlanOptions& opt) {
  const auto tAll = Clock::now();
  checkPlanOptions(opt);
  const std::vector<BarOption> options = barOptions(cage, lms, opt);
  const Measures measures = measuresOf(lms, opt);

  Plan plan;
  plan.target = resolveTarget(cage, lms, opt.analysis);  // refuses a target past the chest line's reach
  measureBefore(cage, measures, opt, plan);

  report(opt, 3, "TetGen (once for every option)");
  const Model model = buildModel(cage, opt.analysis.mesh);
  plan.tets = model.mesh.numTets();
  plan.order = model.mesh.order;
  plan.secondsMesh = model.secondsMesh;

  const int n = static_cast<int>(options.size());
  for (int k = 0; k < n; ++k) {
    Analysis a;
    PlanRow r = analyseOption(cage, model, lms, opt, measures, plan, options[k], k, n, a);
    addRow(opt, std::move(r), a, plan);
  }
  plan.secondsTotal = since(tAll);
  report(opt, 100, "Done");
  return plan;
}

void writePlanCsv(const std::string& path, const Plan& plan) {
  std::FILE* f = openOutput(path);
  std::fprintf(f,
               "option,bars,level,second_level,force_N,elevation_mm,max_stress_MPa,max_stress_at,max_strain,max_strain_at,"
               "slice_gain_cm3,slice_gain_percent,envelope_gain_cm3,envelope_gain_percent,haller_before,haller_after,solves,seconds,best\n");
  for (size_t k = 0; k < plan.rows.size(); ++k) {
    const PlanRow& r = plan.rows[k];
    std::fprintf(f, "%s,%d,%d,%d,%.6g,%.6g,%.6g,%s,%.6g,%s,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%d,%.3f,%d\n", csvField(r.option).c_str(), r.bars,
                 r.level, r.secondLevel, r.force, r.elevation, r.maxStress, csvField(r.maxStressAt).c_str(), r.maxStrain,
                 csvField(r.maxStrainAt).c_str(), r.sliceGain / 1000.0, r.slicePercent, r.envelopeGain / 1000.0, r.envelopePercent,
                 plan.hallerBefore, r.hallerAfter, r.solves, r.seconds, int(k) == plan.best ? 1 : 0);
  }
  closeOutput(f, path);
}

std::vector<std::string> planTable(const Plan& plan) {
  std::vector<std::string> out;
  char b[1024];
  std::snprintf(b, sizeof b, "%-22s %8s %8s %9s %8s %10s %6s %10s %6s %7s  %s", "option", "Fe (N)", "elev mm", "sMax MPa", "eMax",
                "slice cm3", "%", "envel cm3", "%", "Haller", "max stress at / max strain at");
  out.push_back(b);
  for (size_t k = 0; k < plan.rows.size(); ++k) {
    const PlanRow& r = plan.rows[k];
    std::snprintf(b, sizeof b, "%-22s %8s %8s %9s %8s %10s %6s %10s %6s %7s  %s / %s", (r.option + (int(k) == plan.best ? " *" : "")).c_str(),
                  fixedText(r.force, 2).c_str(), fixedText(r.elevation, 2).c_str(), fixedText(r.maxStress, 2).c_str(), fixedText(r.maxStrain, 4).c_str(),
                  fixedText(r.sliceGain / 1000.0, 2).c_str(), fixedText(r.slicePercent, 2).c_str(), fixedText(r.envelopeGain / 1000.0, 2).c_str(),
                  fixedText(r.envelopePercent, 2).c_str(), fixedText(r.hallerAfter, 3).c_str(), r.maxStressWhere.c_str(),
                  r.maxStrainWhere.c_str());
    out.push_back(b);
  }
  return out;
}

}  // namespace pectus::nuss
