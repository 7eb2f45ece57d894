#include "plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

namespace snow {
namespace {

std::string escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '&') out += "&amp;";
    else if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '"') out += "&quot;";
    else out += c;
  }
  return out;
}

std::string decadeLabel(int e) {
  if (e >= -2 && e <= 3) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", std::pow(10.0, e));
    return buf;
  }
  return "1e" + std::to_string(e);
}

std::string minorLabel(double m, int e) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", m * std::pow(10.0, e));
  return buf;
}

}  // namespace

std::string logLogSvg(const std::string& title, const std::string& xLabel, const std::string& yLabel, const std::vector<PlotSeries>& series) {
  const double W = 640, H = 420, left = 80, right = 170, top = 40, bottom = 60;
  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
  int dropped = 0;
  for (const auto& s : series)
    for (const auto& p : s.points) {
      if (!(p.x > 0) || !(p.y > 0)) {
        ++dropped;
        continue;
      }
      x0 = std::min(x0, std::log10(p.x)), x1 = std::max(x1, std::log10(p.x));
      y0 = std::min(y0, std::log10(p.y)), y1 = std::max(y1, std::log10(p.y));
    }
  if (!(x1 >= x0)) x0 = 0, x1 = 1, y0 = 0, y1 = 1;
  // Whole decades around the data, at least one wide.
  x0 = std::floor(x0), x1 = std::max(std::ceil(x1), x0 + 1), y0 = std::floor(y0), y1 = std::max(std::ceil(y1), y0 + 1);
  const double pw = W - left - right, ph = H - top - bottom;
  auto px = [&](double v) { return left + (std::log10(v) - x0) / (x1 - x0) * pw; };
  auto py = [&](double v) { return top + (y1 - std::log10(v)) / (y1 - y0) * ph; };
  const char* colours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b"};
  std::ostringstream o;
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << W << "\" height=\"" << H << "\" font-family=\"sans-serif\" font-size=\"12\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    << "<text x=\"" << W / 2 << "\" y=\"22\" text-anchor=\"middle\" font-size=\"14\">" << escape(title) << "</text>\n";
  // Minor grid lines at 2 and 5 times each decade, labelled when the axis spans two decades or less.
  for (int e = static_cast<int>(x0); e < static_cast<int>(x1); ++e)
    for (double m : {2.0, 5.0}) {
      const double x = left + (e + std::log10(m) - x0) / (x1 - x0) * pw;
      o << "<line x1=\"" << x << "\" y1=\"" << top << "\" x2=\"" << x << "\" y2=\"" << top + ph << "\" stroke=\"#f0f0f0\"/>\n";
      if (x1 - x0 <= 2) o << "<text x=\"" << x << "\" y=\"" << top + ph + 16 << "\" text-anchor=\"middle\" fill=\"#666\">" << minorLabel(m, e) << "</text>\n";
    }
  for (int e = static_cast<int>(y0); e < static_cast<int>(y1); ++e)
    for (double m : {2.0, 5.0}) {
      const double y = top + (y1 - e - std::log10(m)) / (y1 - y0) * ph;
      o << "<line x1=\"" << left << "\" y1=\"" << y << "\" x2=\"" << left + pw << "\" y2=\"" << y << "\" stroke=\"#f0f0f0\"/>\n";
      if (y1 - y0 <= 2) o << "<text x=\"" << left - 6 << "\" y=\"" << y + 4 << "\" text-anchor=\"end\" fill=\"#666\">" << minorLabel(m, e) << "</text>\n";
    }
  for (int e = static_cast<int>(x0); e <= static_cast<int>(x1); ++e) {
    const double x = left + (e - x0) / (x1 - x0) * pw;
    o << "<line x1=\"" << x << "\" y1=\"" << top << "\" x2=\"" << x << "\" y2=\"" << top + ph << "\" stroke=\"#ddd\"/>\n"
      << "<text x=\"" << x << "\" y=\"" << top + ph + 16 << "\" text-anchor=\"middle\">" << decadeLabel(e) << "</text>\n";
  }
  for (int e = static_cast<int>(y0); e <= static_cast<int>(y1); ++e) {
    const double y = top + (y1 - e) / (y1 - y0) * ph;
    o << "<line x1=\"" << left << "\" y1=\"" << y << "\" x2=\"" << left + pw << "\" y2=\"" << y << "\" stroke=\"#ddd\"/>\n"
      << "<text x=\"" << left - 6 << "\" y=\"" << y + 4 << "\" text-anchor=\"end\">" << decadeLabel(e) << "</text>\n";
  }
  o << "<rect x=\"" << left << "\" y=\"" << top << "\" width=\"" << pw << "\" height=\"" << ph << "\" fill=\"none\" stroke=\"black\"/>\n"
    << "<text x=\"" << left + pw / 2 << "\" y=\"" << H - 18 << "\" text-anchor=\"middle\">" << escape(xLabel) << "</text>\n"
    << "<text transform=\"translate(18," << top + ph / 2 << ") rotate(-90)\" text-anchor=\"middle\">" << escape(yLabel) << "</text>\n";
  for (size_t k = 0; k < series.size(); ++k) {
    const char* c = colours[k % 6];
    std::string path;
    for (const auto& p : series[k].points) {
      if (!(p.x > 0) || !(p.y > 0)) continue;
      path += (path.empty() ? "M" : " L") + std::to_string(px(p.x)) + "," + std::to_string(py(p.y));
    }
    if (!path.empty()) o << "<path d=\"" << path << "\" fill=\"none\" stroke=\"" << c << "\" stroke-width=\"1.5\"/>\n";
    for (const auto& p : series[k].points) {
      if (!(p.x > 0) || !(p.y > 0)) continue;
      o << "<circle cx=\"" << px(p.x) << "\" cy=\"" << py(p.y) << "\" r=\"3.5\" fill=\"" << c << "\"/>\n";
      if (!p.label.empty())
        o << "<text x=\"" << px(p.x) + 6 << "\" y=\"" << py(p.y) - 6 << "\" font-size=\"10\" fill=\"" << c << "\">" << escape(p.label) << "</text>\n";
    }
    const double ly = top + 14 + 18 * static_cast<double>(k);
    o << "<line x1=\"" << left + pw + 12 << "\" y1=\"" << ly - 4 << "\" x2=\"" << left + pw + 32 << "\" y2=\"" << ly - 4 << "\" stroke=\"" << c
      << "\" stroke-width=\"2\"/>\n<text x=\"" << left + pw + 36 << "\" y=\"" << ly << "\">" << escape(series[k].name) << "</text>\n";
  }
  if (dropped > 0)
    o << "<text x=\"" << left + pw + 12 << "\" y=\"" << top + ph << "\" font-size=\"10\">" << dropped << " point(s) at 0 not shown</text>\n";
  o << "</svg>\n";
  return o.str();
}

}  // namespace snow
