// A small line plot written as PNG with Qt's QPainter (the adapters' presentation of a core's curve:
// the force-displacement curve of the Nuss analysis, ...). No algorithm here.
#pragma once
#include <string>
#include <utility>
#include <vector>

namespace pectus::ml {

struct PlotSeries {
  std::string label;
  std::vector<std::pair<double, double>> points;
  unsigned rgb = 0x1f77b4;  ///< 0xRRGGBB
  bool markers = true;
};

/// Writes a width x height PNG with axes from 0 (or the data minimum) to the data maximum, ticks,
/// labels and a legend. Horizontal reference lines (e.g. a target) at `hlines`. Throws InputError if
/// the file cannot be written.
void writeLinePlot(const std::string& path, const std::string& title, const std::string& xLabel,
                   const std::string& yLabel, const std::vector<PlotSeries>& series,
                   const std::vector<std::pair<double, std::string>>& hlines = {}, int width = 800, int height = 560);

}  // namespace pectus::ml
