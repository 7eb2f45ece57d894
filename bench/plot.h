// Small SVG plots for the benchmark suite: error against run time on log-log axes, one line per
// series, each point labelled (e.g. with its quality level). Plain SVG 1.1: browsers, GitHub and
// any vector editor open it.
#pragma once
#include <string>
#include <vector>

namespace snow {

struct PlotPoint {
  double x = 0, y = 0;
  std::string label;
};

struct PlotSeries {
  std::string name;
  std::vector<PlotPoint> points;
};

// Log-log plot; points with x or y <= 0 are left out (and the caption says how many).
std::string logLogSvg(const std::string& title, const std::string& xLabel, const std::string& yLabel, const std::vector<PlotSeries>& series);

}  // namespace snow
