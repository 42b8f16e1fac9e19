// Nuss bar planner (the thesis' conclusion): the calibrated Nuss analysis (nuss_analysis.h) for a set of
// bar levels (intercostal spaces) and for one against two bars, with the thoracic volume gain (slice
// method and Ferguson envelope, thoracic_volume.h) and the pectus index after each option, so that
// options can be compared before surgery. Host-free (no Qt).
//
// Options: for every level s and every bar configuration asked for,
//  - one bar in space s: exactly the single analysis (Fe at the lower sternum end, Fsr = Fe/4 on ribs s
//    and s+1 next to the exits of space s);
//  - two bars, the first in s as above, the second in s + secondOffset (default one space above): its
//    sternal patch on the sternum at the lower end's height moved by the height difference of the two
//    bars' exits, its Fsr on ribs s2 and s2+1 next to its exits; the second bar carries `secondShare`
//    of Fe (default half), each bar Fe_i = 2 Fs_i = 4 Fsr_i (Placement::secondSpace).
// Every option is calibrated to the same sternal elevation (the lower sternum end's). The tet mesh is
// built once and reused by every option (only the loads change).
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "pectus/nuss/nuss_analysis.h"
#include "pectus/vol/thoracic_volume.h"

namespace pectus::nuss {

/// "3,4,5" or "3 4 5" or "3-5" -> {3, 4, 5}; throws InputError for an empty list, a non-integer or a
/// space below 1; duplicates are dropped, order kept.
std::vector<int> parseLevels(const std::string& text);

/// PlanOptions::secondOffset (intercostal spaces; 0 is refused as well: both bars in one space)
inline constexpr ParamRange kSecondOffsetRange{-10, 10};

struct PlanOptions {
  std::vector<int> levels;    ///< intercostal spaces of the (first) bar
  bool oneBar = true, twoBars = true;
  int secondOffset = -1;      ///< second bar in space level + secondOffset (negative: above)
  double secondShare = 0.5;   ///< share of Fe on the second bar
  Options analysis;           ///< targetElevation > 0 or targetFromChestLine (the planner always calibrates); place.intercostalSpace is set per option
  vol::SliceParams slice;     ///< range: landmarks 700 (diaphragm dome) .. 701 (lung apex), as the slice filter's default
  vol::EnvelopeParams envelope;  ///< range: landmarks 500 (lower sternum end) .. 701, as the envelope filter's default
  int indexRays = 720;        ///< pectus index at the level of landmark 501 (midline x of 501, spine y of 503)
  enum class Best { LowestForce, LowestStress } best = Best::LowestForce;
  std::function<void(int, const std::string&)> progress;
};

struct PlanRow {
  std::string option;         ///< "1 bar, space 4" / "2 bars, spaces 4 + 3"
  int bars = 1, level = 0, secondLevel = 0;
  double force = 0;           ///< calibrated total Fe (N)
  double elevation = 0;       ///< mm reached at the lower sternum end
  /// the stress away from the joints, load patches and tissue junctions (Analysis::maxStressBody), the strain
  /// away from the joints and load patches (Analysis::maxStrain), as the FE filter's Log
  double maxStress = 0, maxStrain = 0;
  std::string maxStressAt, maxStrainAt;        ///< Location::describe()
  std::string maxStressWhere, maxStrainWhere;  ///< Location::where(): the same without the place
  double sliceGain = 0, slicePercent = 0;        ///< mm^3, %
  double envelopeGain = 0, envelopePercent = 0;  ///< mm^3, %
  double hallerAfter = 0;
  int solves = 0;
  double seconds = 0;         ///< analysis + volumes of this option
};

struct Plan {
  std::vector<PlanRow> rows;
  double sliceBefore = 0, envelopeBefore = 0, hallerBefore = 0;
  Target target;              ///< every option's target elevation, and the chest line
  int best = -1;              ///< row of the best option (PlanOptions::best)
  Analysis bestAnalysis;      ///< its analysis (deformed model, stresses)
  int tets = 0, order = 1;
  double secondsMesh = 0;     ///< TetGen, once
  double secondsTotal = 0;
};

/// Runs every option. Throws InputError before any solve for empty levels, a level outside the ribs
/// (no rib s or s+1), a second bar's offset outside kSecondOffsetRange or 0, a second bar outside the ribs
/// or the sternum, a missing range landmark or a non-positive target; and as the analysis does for anything
/// it refuses.
Plan planBars(const CageSurface& cage, const std::vector<Landmark>& landmarks, const PlanOptions& opt);

/// One line per row, comma-separated, quoted where needed; throws IOError when it cannot be written.
void writePlanCsv(const std::string& path, const Plan& plan);
/// The table as fixed-width text lines (header first), for the Log and the main job.
std::vector<std::string> planTable(const Plan& plan);

}  // namespace pectus::nuss
