#include "pectus/layer_roles.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "pectus/errors.h"
#include "pectus/format.h"

namespace pectus {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

int codeOf(float q) { return int(std::lround(q)); }

bool fitsCode(int code) { return (code > 100 && code < 300) || code == 500 || code == 501; }

std::string listOf(const std::vector<LayerRef>& layers, const std::vector<int>& idx) {
  std::string s;
  for (std::size_t i = 0; i < idx.size(); ++i)
    s += (i == 0 ? "" : i + 1 == idx.size() ? " and " : ", ") + layerText(layers[std::size_t(idx[i])]);
  return s;
}

/// what the named layer is, for the note and the messages
std::string namedText(const std::vector<LayerRef>& layers, int named, const std::string& param) {
  if (named < 0) return "the parameter '" + param + "' names no existing layer";
  return "the parameter '" + param + "' names " + layerText(layers[std::size_t(named)]);
}

bool excluded(const std::vector<int>& exclude, int i) {
  return std::find(exclude.begin(), exclude.end(), i) != exclude.end();
}

/// the landmark layers among `layers` that have the needed codes, nearest to the cage first
struct Ranked {
  int index;
  double distance;
};
std::vector<Ranked> rankLandmarkLayers(const std::vector<LayerRef>& layers, int named, const std::vector<int>& exclude,
                                       const std::vector<const CMeshO*>& surfaces, const std::vector<int>& needed) {
  std::vector<Ranked> out;
  for (int i = 0; i < int(layers.size()); ++i) {
    const LayerRef& l = layers[std::size_t(i)];
    if (i == named || excluded(exclude, i) || l.mesh == nullptr || !landmarkLayerProblem(*l.mesh, needed).empty()) continue;
    out.push_back({i, surfaces.empty() ? kInf : landmarkDistance(*l.mesh, surfaces)});
  }
  std::stable_sort(out.begin(), out.end(), [](const Ranked& a, const Ranked& b) { return a.distance < b.distance; });
  return out;
}

std::string codesText(const std::vector<int>& needed) {
  std::string s;
  for (std::size_t i = 0; i < needed.size(); ++i) s += (i ? ", " : "") + std::to_string(needed[i]);
  return s;
}
}  // namespace

bool isLandmarkCode(int code) {
  const int side = code / 100, rib = code % 100;
  if ((side == 1 || side == 2) && rib >= 1 && rib <= 24) return true;  // costovertebral joints
  if (code >= 500 && code <= 503) return true;
  if (code > 600 && code < 700) {  // bar exits 600 + 10*side + s
    const int s = code - 600, exitSide = s / 10, space = s % 10;
    return (exitSide == 1 || exitSide == 2) && space >= 1;
  }
  return code == 700 || code == 701;
}

std::string landmarkLayerProblem(const CMeshO& m, const std::vector<int>& needed) {
  if (m.fn > 0) return "which is not a landmark layer (it has " + std::to_string(m.fn) + " faces; landmarks are points)";
  if (m.vn == 0) return "which is not a landmark layer (it has no vertices)";
  std::vector<int> codes;
  for (const auto& v : m.vert) {
    if (v.IsD()) continue;
    if (!std::isfinite(v.cQ()) || std::abs(v.cQ() - float(codeOf(v.cQ()))) > 0.01f)
      return "which is not a landmark layer (its vertex quality " + significantText(v.cQ()) + " is no landmark code)";
    codes.push_back(codeOf(v.cQ()));
  }
  if (std::none_of(codes.begin(), codes.end(), isLandmarkCode))
    return "which is not a landmark layer (none of its vertex qualities is a landmark code)";
  std::vector<int> missing;
  for (int c : needed)
    if (std::find(codes.begin(), codes.end(), c) == codes.end()) missing.push_back(c);
  if (!missing.empty()) return "which has no landmark " + codesText(missing);
  return {};
}

double landmarkDistance(const CMeshO& landmarks, const std::vector<const CMeshO*>& surfaces) {
  double worst = -1;
  for (const auto& l : landmarks.vert) {
    if (l.IsD() || !fitsCode(codeOf(l.cQ()))) continue;
    double nearest = kInf;
    for (const CMeshO* s : surfaces)
      for (const auto& v : s->vert)
        if (!v.IsD()) nearest = std::min(nearest, double(vcg::SquaredDistance(v.cP(), l.cP())));
    worst = std::max(worst, std::sqrt(nearest));
  }
  return worst < 0 ? kInf : worst;
}

double landmarkTolerance(const std::vector<const CMeshO*>& surfaces) {
  double sum = 0;
  long n = 0;
  for (const CMeshO* s : surfaces)
    for (const auto& f : s->face) {
      if (f.IsD()) continue;
      for (int k = 0; k < 3; ++k) sum += double(vcg::Distance(f.cP(k), f.cP((k + 1) % 3)));
      n += 3;
    }
  return std::max(10.0, n ? 3 * sum / double(n) : 0.0);
}

LayerChoice chooseLandmarkLayer(const std::vector<LayerRef>& layers, int named, const std::vector<int>& exclude,
                                const std::vector<const CMeshO*>& surfaces, const std::vector<int>& needed,
                                const std::string& param, const std::string& hint) {
  const double tol = landmarkTolerance(surfaces);
  const auto others = rankLandmarkLayers(layers, named, exclude, surfaces, needed);
  const bool otherFits = !others.empty() && others.front().distance <= tol;
  std::string why;  // why the named layer is not taken
  if (named >= 0 && excluded(exclude, named)) {
    why = "which is the cage itself, not a landmark layer";
  } else if (named >= 0 && layers[std::size_t(named)].mesh != nullptr) {
    const LayerRef& n = layers[std::size_t(named)];
    why = landmarkLayerProblem(*n.mesh, needed);
    if (why.empty()) {
      const double d = surfaces.empty() ? 0 : landmarkDistance(*n.mesh, surfaces);
      if (d <= tol || !otherFits) return {named, {}};
      why = "whose landmarks lie " + fixedText(d, 1) + " mm from the cage (another layer's lie on it)";
    }
  }
  const std::string namedNote = namedText(layers, named, param) + (why.empty() ? "" : ", " + why);
  const std::string want = needed.empty() ? "" : " with landmark " + codesText(needed);
  if (others.empty())
    throw InputError("no landmark layer" + want + ": " + namedNote +
                     ", and no other layer is a point layer of landmark codes (vertex quality, labels.h) with them." +
                     (hint.empty() ? "" : " " + hint));
  const bool clear = others.size() == 1 || (otherFits && others[1].distance > tol) ||
                     (others.front().distance <= tol && others.front().distance <= 0.5 * others[1].distance);
  if (!clear) {
    std::vector<int> idx;
    for (const auto& r : others) idx.push_back(r.index);
    throw InputError("which landmark layer? " + namedNote + "; " + std::to_string(idx.size()) + " layers could be the cage's landmarks: " +
                     listOf(layers, idx) + ". Choose one as '" + param + "' (in a script: its number)." +
                     (hint.empty() ? "" : " " + hint));
  }
  return {others.front().index, namedNote};
}

std::string beforeLayerProblem(const CMeshO& m, const CMeshO& measured) {
  if (m.fn == 0) return "which has no faces";
  if (m.vn != measured.vn)
    return "which is not the same model (" + std::to_string(m.vn) + " vertices; the measured layer has " + std::to_string(measured.vn) + ")";
  return {};
}

LayerChoice chooseBeforeLayer(const std::vector<LayerRef>& layers, int named, int current, int recorded,
                              const std::string& param) {
  const CMeshO& measured = *layers[std::size_t(current)].mesh;
  auto can = [&](int i) {
    return i >= 0 && i != current && layers[std::size_t(i)].mesh != nullptr &&
           beforeLayerProblem(*layers[std::size_t(i)].mesh, measured).empty();
  };
  if (can(named)) return {named, {}};
  std::string why;
  if (named == current) why = ", the measured (current) layer itself";
  else if (named >= 0 && layers[std::size_t(named)].mesh != nullptr)
    why = ", " + beforeLayerProblem(*layers[std::size_t(named)].mesh, measured);
  const std::string namedNote = namedText(layers, named, param) + why;
  if (can(recorded)) return {recorded, namedNote + "; the measured layer was computed from it"};
  std::vector<int> idx;
  for (int i = 0; i < int(layers.size()); ++i)
    if (can(i)) idx.push_back(i);
  const std::string cur = layerText(layers[std::size_t(current)]);
  if (idx.empty())
    throw InputError("no before layer for " + cur + ": " + namedNote + ", and no other layer is the same model (" +
                     std::to_string(measured.vn) + " vertices), as the cage an FE result was computed from is. Load or choose the before state, or turn "
                     "'Compare' off.");
  if (idx.size() > 1)
    throw InputError("which before layer? " + namedNote + "; " + std::to_string(idx.size()) + " layers are the same mesh as " +
                     cur + ": " + listOf(layers, idx) + ". Choose one as '" + param + "' (in a script: its number).");
  return {idx.front(), namedNote};
}

std::string layerText(const LayerRef& l) { return "layer " + std::to_string(l.number) + " '" + l.label + "'"; }

}  // namespace pectus
