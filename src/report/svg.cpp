// Inline SVG plots for the HTML report: bar charts, radar charts and latency CDFs.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>

#include "report_model.hpp"

namespace robotperf::report::detail {
namespace {

// 11 px text: about 6.5 px per character.
constexpr double kLabelCharWidth = 6.5;

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", v);
  return buf;
}

// A "nice" tick step (1, 2 or 5 times a power of ten) for about `count` ticks over `range`.
double nice_step(double range, int count) {
  if (!(range > 0)) return 1;
  const double raw = range / count;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (raw <= m * magnitude) return m * magnitude;
  }
  return 10 * magnitude;
}

// A series name that fits the legend: long ones lose their middle, not their end, since what
// tells two series of one machine apart (transport, layout, rate) is at the end. The full name is
// the entry's title.
std::string legend_label(const std::string& name, std::size_t max = 68) {
  const std::size_t head_size = max * 38 / 68;
  if (name.size() <= max) return name;
  auto boundary = [&](std::size_t at) {  // not inside a UTF-8 sequence
    while (at > 0 && (static_cast<unsigned char>(name[at]) & 0xC0) == 0x80) --at;
    return at;
  };
  const std::size_t head = boundary(head_size);
  const std::size_t tail = boundary(name.size() - (max - head_size - 1));
  return name.substr(0, head) + "…" + name.substr(tail);
}

// The legend of a radar or bar chart, from `top`: one entry per series, then the omitted count.
void legend(std::ostringstream& s, const Radar& r, double top) {
  double ly = top;
  for (std::size_t si = 0; si < r.series.size(); ++si) {
    const char* colour = colour_of(r.colours[si]);
    s << "<rect x=\"20\" y=\"" << num(ly - 10) << "\" width=\"14\" height=\"10\" fill=\"" << colour
      << "\"/><text class=\"legend\" x=\"40\" y=\"" << num(ly) << "\">"
      << html_escape(legend_label(r.series[si])) << "<title>" << html_escape(r.series[si])
      << "</title></text>\n";
    ly += 18;
  }
  if (!r.omitted.empty()) {
    s << "<text class=\"legend\" x=\"20\" y=\"" << num(ly) << "\">+ " << r.omitted.size()
      << " more platforms (in the table below)</text>\n";
  }
}

// What radar_svg draws where a polygon would say nothing (drawn_as_bars): one group of bars per
// benchmark, one bar per series, each group on its own linear scale from 0, the value written at
// the bar's end.
std::string bars_svg(const Radar& r) {
  constexpr double kWidth = 480, kLeft = 20, kBarsLeft = 20, kBarsWidth = 330, kBar = 14;
  const std::size_t n = r.axes.size();
  std::size_t drawn = 0;
  double height = 40;
  for (std::size_t a = 0; a < n; ++a) {
    height += 24;
    for (const auto& row : r.values) height += std::isfinite(row[a]) ? kBar + 4 : 0;
  }
  const double legend_top = height + 20;
  const double total =
      legend_top + 18.0 * static_cast<double>(r.series.size() + (r.omitted.empty() ? 0 : 1));
  std::ostringstream s;
  s << "<svg class=\"bars\" data-category=\"" << html_escape(r.category) << "\" data-metric=\""
    << r.metric << "\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << kWidth << "\" height=\""
    << num(total) << "\" viewBox=\"0 0 " << kWidth << " " << num(total) << "\" role=\"img\">\n";
  s << "<title>" << html_escape(r.category + ": " + r.metric + " (" + r.unit + ")") << "</title>\n";
  s << "<text x=\"" << kWidth / 2 << "\" y=\"22\" text-anchor=\"middle\" class=\"plot-title\">"
    << html_escape((r.figure.empty() ? r.metric : r.figure) + " (" + r.unit + ") — " +
                   (r.smaller_is_better ? "smaller is better" : "larger is better"))
    << "</text>\n";
  double y = 40;
  for (std::size_t a = 0; a < n; ++a) {
    double axis_max = 0;
    for (const auto& row : r.values) {
      if (std::isfinite(row[a])) axis_max = std::max(axis_max, row[a]);
    }
    y += 16;
    s << "<text class=\"axis-label\" x=\"" << kLeft << "\" y=\"" << num(y) << "\">"
      << html_escape(r.axes[a]) << " (" << r.unit << ")</text>\n";
    y += 8;
    for (std::size_t si = 0; si < r.series.size(); ++si) {
      const double v = r.values[si][a];
      if (!std::isfinite(v)) continue;
      const char* colour = colour_of(r.colours[si]);
      const double w = axis_max > 0 && v > 0 ? kBarsWidth * (v / axis_max) : 0;
      s << "<rect class=\"bar\" x=\"" << kBarsLeft << "\" y=\"" << num(y) << "\" width=\""
        << num(std::max(w, 1.0)) << "\" height=\"" << kBar << "\" fill=\"" << colour
        << "\" fill-opacity=\"" << (r.series_local[si] ? "0.85" : "0.35") << "\" stroke=\""
        << colour << "\"" << (r.series_local[si] ? "" : " stroke-dasharray=\"5,3\"") << "><title>"
        << html_escape(r.series[si]) << ": " << format_value(v) << " " << r.unit
        << "</title></rect>\n";
      s << "<text class=\"tick\" x=\"" << num(kBarsLeft + w + 6) << "\" y=\"" << num(y + kBar - 3)
        << "\">" << format_value(v) << "</text>\n";
      y += kBar + 4;
      ++drawn;
    }
  }
  legend(s, r, legend_top);
  s << "</svg>\n";
  return drawn > 0 ? s.str() : std::string();
}

// How many series have a value on each axis.
std::vector<std::size_t> values_on_axes(const Radar& r) {
  std::vector<std::size_t> on_axis(r.axes.size(), 0);
  for (const auto& row : r.values) {
    for (std::size_t a = 0; a < r.axes.size(); ++a)
      on_axis[a] += std::isfinite(row[a]) && row[a] > 0;
  }
  return on_axis;
}

}  // namespace

bool drawn_as_bars(const Radar& r) {
  // Each axis is scaled to its own values: with no axis holding two, a polygon would only say
  // "every value is its axis' maximum". Bars show the values themselves.
  const auto on_axis = values_on_axes(r);
  return r.axes.size() < 3 || std::ranges::max(on_axis) < 2;
}

void place_labels(std::vector<Label>& labels) {
  constexpr double kLineHeight = 12;  // from one baseline to the next line's, 11 px text
  auto overlap = [&](const Label& a, const Label& b) {
    const double aw = kLabelCharWidth * static_cast<double>(a.text.size());
    const double bw = kLabelCharWidth * static_cast<double>(b.text.size());
    return a.x < b.x + bw && b.x < a.x + aw && a.y - kLineHeight < b.y && b.y - kLineHeight < a.y;
  };
  for (std::size_t i = 0; i < labels.size(); ++i) {
    // Lower, one line at a time, until clear of every label placed before it.
    for (bool moved = true; moved;) {
      moved = false;
      for (std::size_t j = 0; j < i; ++j) {
        if (overlap(labels[i], labels[j])) {
          labels[i].y = labels[j].y + kLineHeight + 1;
          moved = true;
        }
      }
    }
  }
}

std::string radar_svg(const Radar& r) {
  constexpr double kSize = 480, kCx = 240, kCy = 200, kRadius = 120;
  const std::size_t n = r.axes.size();
  if (drawn_as_bars(r)) return bars_svg(r);
  const std::vector<std::size_t> on_axis = values_on_axes(r);
  const double legend_height =
      18.0 * static_cast<double>(r.series.size() + (r.omitted.empty() ? 0 : 1)) + 10;
  std::ostringstream s;
  s << "<svg class=\"radar\" data-category=\"" << html_escape(r.category) << "\" data-metric=\""
    << r.metric << "\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << kSize << "\" height=\""
    << num(400 + legend_height) << "\" viewBox=\"0 0 " << kSize << " " << num(400 + legend_height)
    << "\" role=\"img\">\n";
  s << "<title>" << html_escape(r.category + ": " + r.metric + " (" + r.unit + ")") << "</title>\n";
  s << "<text x=\"" << kCx << "\" y=\"22\" text-anchor=\"middle\" class=\"plot-title\">"
    << html_escape((r.figure.empty() ? r.metric : r.figure) + " (" + r.unit + ") — " +
                   (r.smaller_is_better ? "smaller is better" : "larger is better"))
    << "</text>\n";
  // Each axis has its own scale so that benchmarks of different magnitude share the plot: linear
  // from 0 to the axis maximum, or, when the values of that axis span more than a factor of 20
  // (published data has outliers), logarithmic from the axis minimum (at 10 % of the radius) to
  // the maximum. Either way a smaller value sits nearer the centre. The scale is written at the
  // end of each axis.
  std::vector<double> axis_min(n, 0.0), axis_max(n, 0.0);
  for (std::size_t a = 0; a < n; ++a) {
    bool any = false;
    for (const auto& row : r.values) {
      if (!std::isfinite(row[a]) || row[a] <= 0) continue;
      axis_min[a] = any ? std::min(axis_min[a], row[a]) : row[a];
      axis_max[a] = any ? std::max(axis_max[a], row[a]) : row[a];
      any = true;
    }
  }
  // Decided per axis: a 10 % difference on one axis must not be drawn as 10x because another
  // axis needed a logarithmic scale.
  auto logarithmic = [&](std::size_t a) { return axis_max[a] > 20 * axis_min[a]; };
  // An axis with one value has nothing to scale it against: its point sits mid-way, not on the
  // rim where it would read as the worst, and the axis says "only".
  auto fraction = [&](std::size_t a, double v) {
    if (on_axis[a] == 1) return 0.5;
    if (!logarithmic(a)) return v / axis_max[a];
    return 0.1 + 0.9 * std::log(v / axis_min[a]) / std::log(axis_max[a] / axis_min[a]);
  };
  auto angle = [&](std::size_t a) {
    return -std::numbers::pi / 2 +
           2 * std::numbers::pi * static_cast<double>(a) / static_cast<double>(n);
  };
  auto point = [&](std::size_t a, double f) {
    return std::pair{kCx + kRadius * f * std::cos(angle(a)),
                     kCy + kRadius * f * std::sin(angle(a))};
  };
  // Grid rings.
  for (double ring : {0.25, 0.5, 0.75, 1.0}) {
    s << "<polygon class=\"grid\" points=\"";
    for (std::size_t a = 0; a < n; ++a) {
      const auto [x, y] = point(a, ring);
      s << num(x) << "," << num(y) << " ";
    }
    s << "\" fill=\"none\" stroke=\"#ccc\"/>\n";
  }
  // Axes with their labels.
  for (std::size_t a = 0; a < n; ++a) {
    const auto [x, y] = point(a, 1.0);
    s << "<line x1=\"" << kCx << "\" y1=\"" << kCy << "\" x2=\"" << num(x) << "\" y2=\"" << num(y)
      << "\" stroke=\"#999\"/>\n";
    const auto [lx, ly] = point(a, 1.16);
    const double c = std::cos(angle(a));
    const char* anchor = c > 0.3 ? "start" : c < -0.3 ? "end" : "middle";
    s << "<text class=\"axis-label\" x=\"" << num(lx) << "\" y=\"" << num(ly) << "\" text-anchor=\""
      << anchor << "\">" << html_escape(r.axes[a]) << " (" << r.unit << ")</text>\n";
    s << "<text class=\"axis-scale\" x=\"" << num(lx) << "\" y=\"" << num(ly + 13)
      << "\" text-anchor=\"" << anchor << "\">"
      << (on_axis[a] == 1  ? "only " + format_value(axis_max[a])
          : logarithmic(a) ? format_value(axis_min[a]) + "–" + format_value(axis_max[a]) + " (log)"
                           : "max " + format_value(axis_max[a]))
      << "</text>\n";
  }
  // One polygon per series; a series without a value on some axis is a gap there: lines join only
  // neighbouring axes that both have one, so no line crosses an axis it has no value on.
  for (std::size_t si = 0; si < r.series.size(); ++si) {
    const char* colour = colour_of(r.colours[si]);
    std::vector<std::optional<std::pair<double, double>>> at(n);
    std::vector<std::pair<double, double>> pts;
    for (std::size_t a = 0; a < n; ++a) {
      const double v = r.values[si][a];
      if (!std::isfinite(v) || v <= 0 || axis_max[a] <= 0) continue;
      at[a] = point(a, fraction(a, v));
      pts.push_back(*at[a]);
    }
    const std::string stroke = std::string("stroke=\"") + colour + "\" stroke-width=\"" +
                               (r.series_local[si] ? "3" : "1.5") + "\"" +
                               (r.series_local[si] ? "" : " stroke-dasharray=\"5,3\"");
    if (pts.size() == n) {
      s << "<polygon class=\"series\" points=\"";
      for (const auto& [x, y] : pts) s << num(x) << "," << num(y) << " ";
      s << "\" fill=\"" << colour << "\" fill-opacity=\"0.12\" " << stroke << "/>\n";
    } else if (pts.size() >= 2) {
      for (std::size_t a = 0; a < n; ++a) {
        const std::size_t b = (a + 1) % n;
        if (!at[a] || !at[b]) continue;
        s << "<line class=\"series-part\" x1=\"" << num(at[a]->first) << "\" y1=\""
          << num(at[a]->second) << "\" x2=\"" << num(at[b]->first) << "\" y2=\""
          << num(at[b]->second) << "\" " << stroke << "/>\n";
      }
    }
    for (const auto& [x, y] : pts) {
      s << "<circle cx=\"" << num(x) << "\" cy=\"" << num(y) << "\" r=\""
        << (r.series_local[si] ? 5 : 3.5) << "\" fill=\"" << colour << "\"/>\n";
    }
  }
  legend(s, r, 400);
  s << "</svg>\n";
  return s.str();
}

std::string bar_chart_svg(const BarChart& chart) {
  // Names left of the bars (the bars' legend: no colour is needed to tell them apart), one scale,
  // the value right of each bar's whisker. The page's filter script hides rows and closes the
  // gaps: it reads the row pitch and the top from the svg's data attributes.
  constexpr double kWidth = 760, kBarsLeft = 330, kBarsWidth = 340, kTop = 34, kRow = 22;
  constexpr double kBar = 14;
  if (chart.bars.empty()) return "";
  double x_min = std::numeric_limits<double>::max(), x_max = 0;
  for (const auto& b : chart.bars) {
    std::vector<double> drawn = b.points;
    drawn.insert(drawn.end(), {b.value, b.lower, b.upper});
    for (double v : drawn) {
      if (!std::isfinite(v) || v <= 0) continue;
      x_min = std::min(x_min, v);
      x_max = std::max(x_max, v);
    }
  }
  if (!(x_max > 0)) return "";
  x_max = std::min(x_max, std::numeric_limits<double>::max() / 4);
  // Published rows span boards and servers: beyond 50x, a linear scale would flatten all but the
  // slowest bars, so the scale is logarithmic, from the power of ten below the smallest value
  // (where every bar starts) to the one above the largest, and the axis says so.
  const bool logarithmic = x_max > 50 * x_min;
  const double step = nice_step(x_max, 5);
  // The decade below the smallest value, also when that value is a power of ten: its bar shows.
  const double decade_low = std::ceil(std::log10(x_min)) - 1;
  const double decade_high = std::ceil(std::log10(x_max));
  if (!logarithmic) x_max = std::max(step, std::ceil(x_max / step) * step);
  auto px = [&](double v) {
    if (!logarithmic) return kBarsLeft + kBarsWidth * (std::max(v, 0.0) / x_max);
    const double at =
        (std::max(std::log10(v), decade_low) - decade_low) / (decade_high - decade_low);
    return kBarsLeft + kBarsWidth * at;
  };
  std::vector<double> ticks;
  if (logarithmic) {
    for (double d = decade_low; d <= decade_high; ++d) ticks.push_back(std::pow(10.0, d));
  } else {
    for (int k = 0; k <= static_cast<int>(std::lround(x_max / step)); ++k)
      ticks.push_back(k * step);
  }
  const double rows = static_cast<double>(chart.bars.size());
  const double height = kTop + kRow * rows + 48;
  std::ostringstream s;
  s << "<svg class=\"barchart\" data-benchmark=\"" << html_escape(chart.benchmark)
    << "\" data-figure=\"" << chart.figure << "\" data-top=\"" << kTop << "\" data-row=\"" << kRow
    << "\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << kWidth << "\" height=\"" << num(height)
    << "\" viewBox=\"0 0 " << kWidth << " " << num(height) << "\" role=\"img\">\n";
  const std::string pattern = "hatch-" + chart.benchmark + "-" + chart.figure;
  s << "<defs><pattern id=\"" << html_escape(pattern)
    << "\" width=\"6\" height=\"6\" patternUnits=\"userSpaceOnUse\" "
       "patternTransform=\"rotate(45)\"><rect width=\"6\" height=\"6\" fill=\"#fff\"/><line "
       "x1=\"0\" y1=\"0\" x2=\"0\" y2=\"6\" stroke=\"#666\" "
       "stroke-width=\"2.5\"/></pattern></defs>\n";
  s << "<title>" << html_escape(chart.benchmark + ": " + chart.axis) << "</title>\n";
  s << "<text class=\"plot-title\" x=\"8\" y=\"18\">"
    << html_escape(chart.benchmark + ": " + chart.figure +
                   " latency per configuration — smaller is better")
    << "</text>\n";
  double y = kTop;
  for (const auto& b : chart.bars) {
    const char* colour = colour_of(b.colour);
    const bool coloured = b.colour != kNoColour;
    s << "<g class=\"bar-row\" data-series=\"" << html_escape(b.series) << "\" data-colour=\""
      << (coloured ? colour : "none") << "\"";
    for (const auto& [group, value] : b.tags)
      s << " data-" << group << "=\"" << html_escape(value) << "\"";
    s << " transform=\"translate(0," << num(y) << ")\">\n";
    s << "<text class=\"tick\" x=\"" << num(kBarsLeft - 8) << "\" y=\"12\" text-anchor=\"end\">"
      << html_escape(legend_label(b.series, 42)) << "<title>"
      << html_escape(b.series + (b.local ? " (local runs, " : " (published RobotPerf rows, ") +
                     b.count + ")")
      << "</title></text>\n";
    // Local runs solid, published rows hatched: told apart by more than colour.
    const double end = px(b.value);
    s << "<rect class=\"bar" << (b.local ? " local" : " published") << "\" x=\"" << kBarsLeft
      << "\" y=\"" << num((kRow - kBar) / 2 - 2) << "\" width=\""
      << num(std::max(end - kBarsLeft, 1.0)) << "\" height=\"" << kBar << "\" fill=\""
      << (b.local ? (coloured ? colour : "#ffffff") : "url(#" + html_escape(pattern) + ")")
      << "\" stroke=\"" << (coloured ? colour : "#333333") << "\" stroke-width=\""
      << (b.local ? "1" : "2.5") << "\"><title>" << html_escape(b.series) << ": "
      << format_value(b.value) << " ms (" << html_escape(b.count) << ")</title></rect>\n";
    double right = end;
    if (std::isfinite(b.lower) && std::isfinite(b.upper)) {
      const double mid = kRow / 2 - 2;
      s << "<path class=\"whisker\" d=\"M" << num(px(b.lower)) << " " << num(mid) << "H"
        << num(px(b.upper)) << "M" << num(px(b.lower)) << " " << num(mid - 5) << "v10M"
        << num(px(b.upper)) << " " << num(mid - 5) << "v10\" stroke=\"#222\" fill=\"none\"/>\n";
      right = std::max(right, px(b.upper));
    }
    for (double v : b.points) {
      if (!std::isfinite(v)) continue;
      s << "<circle class=\"run\" cx=\"" << num(px(v)) << "\" cy=\"" << num(kRow / 2 - 2)
        << "\" r=\"3\" fill=\"#fff\" stroke=\"#222\"/>\n";
      right = std::max(right, px(v));
    }
    s << "<text class=\"tick\" x=\"" << num(right + 5) << "\" y=\"12\">" << format_value(b.value)
      << "</text>\n</g>\n";
    y += kRow;
  }
  s << "<g class=\"axis\" transform=\"translate(0," << num(y + 4) << ")\">\n";
  s << "<line x1=\"" << kBarsLeft << "\" x2=\"" << num(kBarsLeft + kBarsWidth)
    << "\" y1=\"0\" y2=\"0\" stroke=\"#666\"/>\n";
  for (double tick : ticks) {
    const double x = px(tick);
    s << "<line x1=\"" << num(x) << "\" x2=\"" << num(x) << "\" y1=\"0\" y2=\"4\" stroke=\"#666\"/>"
      << "<text class=\"tick\" x=\"" << num(x) << "\" y=\"16\" text-anchor=\"middle\">"
      << format_value(tick) << "</text>\n";
  }
  s << "<text class=\"axis-label\" x=\"" << num(kBarsLeft + kBarsWidth / 2) << "\" y=\"36\" "
    << "text-anchor=\"middle\">"
    << html_escape(chart.figure + " latency (ms" + (logarithmic ? ", log scale)" : ")"))
    << "<title>" << html_escape(chart.axis) << "</title></text>\n</g>\n</svg>\n";
  return s.str();
}

std::string hops_svg(const std::vector<StoredRun::Hop>& hops, const std::string& run) {
  // A graph's hops are no chain (a node has a path per input and output, a kernel runs inside its
  // node), so their durations are drawn side by side, never stacked: one bar per hop, its mean,
  // with a whisker to its p99, coloured by kind, on one linear scale from 0.
  constexpr double kWidth = 760, kLabelsLeft = 10, kBarsLeft = 370, kBarsWidth = 300, kRow = 18;
  // Shades of grey: a hop's kind is no series, and must not take a series' colour.
  constexpr std::pair<const char*, const char*> kKinds[] = {
      {"transport", "#333333"}, {"node", "#777777"}, {"kernel", "#aaaaaa"}, {"device", "#cccccc"}};
  auto colour_of = [&](const std::string& kind) {
    for (const auto& [k, c] : kKinds) {
      if (kind == k) return c;
    }
    return "#e6e6e6";
  };
  double x_max = 0;
  for (const auto& h : hops) {
    for (double v : {h.mean_ms, h.p99_ms}) {
      if (std::isfinite(v)) x_max = std::max(x_max, v);
    }
  }
  if (hops.empty() || !(x_max > 0)) return "";
  const double top = 40;
  const double height = top + kRow * static_cast<double>(hops.size()) + 40;
  auto px = [&](double v) { return kBarsLeft + kBarsWidth * (v / x_max); };
  std::ostringstream s;
  s << "<svg class=\"hops\" data-run=\"" << html_escape(run)
    << "\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << kWidth << "\" height=\"" << num(height)
    << "\" viewBox=\"0 0 " << kWidth << " " << num(height) << "\" role=\"img\">\n";
  s << "<title>" << html_escape(run) << ": per-hop durations</title>\n";
  s << "<text class=\"plot-title\" x=\"" << kLabelsLeft << "\" y=\"18\">"
    << html_escape("per hop: mean duration (ms), whisker to p99 — " + run) << "</text>\n";
  double y = top;
  for (const auto& h : hops) {
    const char* colour = colour_of(h.kind);
    s << "<text class=\"tick\" x=\"" << kLabelsLeft << "\" y=\"" << num(y + 12) << "\">"
      << html_escape(legend_label(h.label, 54)) << "<title>"
      << html_escape(h.label + " (" + h.kind + ")") << "</title></text>\n";
    double end = kBarsLeft;
    if (std::isfinite(h.mean_ms)) {
      end = px(h.mean_ms);
      s << "<rect class=\"bar\" x=\"" << kBarsLeft << "\" y=\"" << num(y + 3) << "\" width=\""
        << num(std::max(end - kBarsLeft, 1.0)) << "\" height=\"12\" fill=\"" << colour
        << "\"><title>" << html_escape(h.label) << ": mean " << format_value(h.mean_ms)
        << " ms</title></rect>\n";
    }
    if (std::isfinite(h.p99_ms)) {
      end = std::max(end, px(h.p99_ms));
      s << "<line x1=\"" << num(px(std::isfinite(h.mean_ms) ? h.mean_ms : 0)) << "\" x2=\""
        << num(px(h.p99_ms)) << "\" y1=\"" << num(y + 9) << "\" y2=\"" << num(y + 9)
        << "\" stroke=\"#444\"/><line x1=\"" << num(px(h.p99_ms)) << "\" x2=\"" << num(px(h.p99_ms))
        << "\" y1=\"" << num(y + 5) << "\" y2=\"" << num(y + 13) << "\" stroke=\"#444\"/>\n";
    }
    s << "<text class=\"tick\" x=\"" << num(end + 4) << "\" y=\"" << num(y + 12) << "\">"
      << format_value(h.mean_ms) << "</text>\n";
    y += kRow;
  }
  // The colours of the kinds drawn, under the bars.
  double lx = kBarsLeft;
  for (const auto& [kind, colour] : kKinds) {
    // A named copy: clang before 16 cannot capture a structured binding.
    const auto& drawn = kind;
    if (std::none_of(hops.begin(), hops.end(), [&](const auto& h) { return h.kind == drawn; }))
      continue;
    s << "<rect x=\"" << num(lx) << "\" y=\"" << num(y + 12)
      << "\" width=\"14\" height=\"10\" fill=\"" << colour << "\"/><text class=\"legend\" x=\""
      << num(lx + 18) << "\" y=\"" << num(y + 21) << "\">" << kind << "</text>\n";
    lx += 90;
  }
  s << "</svg>\n";
  return s.str();
}

std::string distribution_svg(const std::vector<Distribution>& curves, const std::string& id) {
  constexpr double kWidth = 760, kLeft = 60, kRight = 20, kTop = 30, kPlotHeight = 240;
  const double legend_height = 18.0 * static_cast<double>(curves.size()) + 10;
  const double height = kTop + kPlotHeight + 45 + legend_height;
  // The axis ends a little past the largest latency, held well inside double's range so that
  // the margin and the rounding up to a whole step stay finite.
  double x_max = 0;
  for (const auto& c : curves) {
    for (const auto& [x, y] : c.points) {
      if (std::isfinite(x)) x_max = std::max(x_max, x);
    }
  }
  x_max = std::min(x_max, std::numeric_limits<double>::max() / 4);
  const double step = nice_step(x_max, 8);
  x_max = std::max(step, std::ceil(x_max * 1.02 / step) * step);
  const int ticks = static_cast<int>(std::lround(x_max / step));
  const double plot_width = kWidth - kLeft - kRight;
  auto px = [&](double x) { return kLeft + plot_width * (x / x_max); };  // no overflow
  auto py = [&](double y) { return kTop + kPlotHeight * (1 - y); };
  std::ostringstream s;
  s << "<svg class=\"cdf\" data-benchmark=\"" << html_escape(id)
    << "\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << kWidth << "\" height=\"" << num(height)
    << "\" viewBox=\"0 0 " << kWidth << " " << num(height) << "\" role=\"img\">\n";
  s << "<title>" << html_escape(id) << " latency distribution</title>\n";
  s << "<text class=\"plot-title\" x=\"" << kLeft << "\" y=\"18\">" << html_escape(id)
    << ": latency from the scheduled send, cumulative distribution (p50 and p99 marked)</text>\n";
  // Axes and grid.
  for (double y : {0.0, 0.25, 0.5, 0.75, 0.9, 1.0}) {
    s << "<line x1=\"" << kLeft << "\" x2=\"" << num(kLeft + plot_width) << "\" y1=\"" << num(py(y))
      << "\" y2=\"" << num(py(y)) << "\" stroke=\"#eee\"/>\n";
    s << "<text class=\"tick\" x=\"" << num(kLeft - 6) << "\" y=\"" << num(py(y) + 4)
      << "\" text-anchor=\"end\">" << y << "</text>\n";
  }
  for (int k = 0; k <= ticks; ++k) {
    const double x = k * step;
    s << "<line x1=\"" << num(px(x)) << "\" x2=\"" << num(px(x)) << "\" y1=\"" << num(py(0))
      << "\" y2=\"" << num(py(0) + 5) << "\" stroke=\"#666\"/>\n";
    s << "<text class=\"tick\" x=\"" << num(px(x)) << "\" y=\"" << num(py(0) + 18)
      << "\" text-anchor=\"middle\">" << format_value(x) << "</text>\n";
  }
  s << "<text class=\"tick\" x=\"" << num(kLeft + plot_width / 2) << "\" y=\"" << num(py(0) + 36)
    << "\" text-anchor=\"middle\">latency (ms)</text>\n";
  s << "<text class=\"tick\" x=\"14\" y=\"" << num(kTop + kPlotHeight / 2)
    << "\" text-anchor=\"middle\" transform=\"rotate(-90 14 " << num(kTop + kPlotHeight / 2)
    << ")\">fraction of messages</text>\n";
  s << "<rect x=\"" << kLeft << "\" y=\"" << kTop << "\" width=\"" << num(plot_width)
    << "\" height=\"" << kPlotHeight << "\" fill=\"none\" stroke=\"#666\"/>\n";
  std::vector<Label> labels;  // the p50 and p99 markers' values, placed once all are known
  // Each curve in its configuration's colour; INVALID runs grey and dashed, never a colour a
  // valid run could be read as. Further runs of one configuration are told apart by their dashes.
  auto curve_colour = [&](std::size_t i) {
    return curves[i].valid ? colour_of(curves[i].colour) : "#999999";
  };
  std::vector<const char*> dashes;
  for (std::size_t i = 0; i < curves.size(); ++i) {
    constexpr const char* kDashes[] = {"", " stroke-dasharray=\"2,2\"", " stroke-dasharray=\"8,3\"",
                                       " stroke-dasharray=\"8,3,2,3\""};
    std::size_t before = 0;
    for (std::size_t j = 0; j < i; ++j)
      before += curves[j].valid && curves[j].series == curves[i].series;
    dashes.push_back(curves[i].valid ? kDashes[before % 4] : " stroke-dasharray=\"6,4\"");
  }
  for (std::size_t i = 0; i < curves.size(); ++i) {
    const auto& c = curves[i];
    const char* colour = curve_colour(i);
    s << "<polyline class=\"curve" << (c.valid ? "" : " invalid") << "\" data-series=\""
      << html_escape(c.series) << "\" fill=\"none\" stroke=\"" << colour << "\" stroke-width=\"2\""
      << dashes[i] << " points=\"";
    // A CDF is a step function: draw each rise at its x.
    double last_y = 0;
    bool first = true;
    for (const auto& [x, y] : c.points) {
      if (first) {
        s << num(px(x)) << "," << num(py(0)) << " ";
        first = false;
      }
      s << num(px(x)) << "," << num(py(last_y)) << " " << num(px(x)) << "," << num(py(y)) << " ";
      last_y = y;
    }
    s << "\"/>\n";
    for (const auto& [q, v] : {std::pair{0.5, c.p50}, {0.99, c.p99}}) {
      if (!std::isfinite(v)) continue;
      s << "<line class=\"marker\" x1=\"" << num(px(v)) << "\" x2=\"" << num(px(v)) << "\" y1=\""
        << num(py(0)) << "\" y2=\"" << num(py(q)) << "\" stroke=\"" << colour
        << "\" stroke-dasharray=\"4,3\"/>\n";
      s << "<circle cx=\"" << num(px(v)) << "\" cy=\"" << num(py(q)) << "\" r=\"4\" fill=\""
        << colour << "\"/>\n";
      std::string text = std::string(q == 0.5 ? "p50 " : "p99 ") + format_value(v);
      // Right of the marker, or left of it where the text would run past the plot's edge.
      const double width = kLabelCharWidth * static_cast<double>(text.size());
      const double x = px(v) + 5 + width <= kWidth - 2 ? px(v) + 5 : px(v) - 5 - width;
      labels.push_back({x, py(q) + (q > 0.9 ? 14 : -6), std::move(text), colour});
    }
  }
  place_labels(labels);
  for (const auto& l : labels) {
    s << "<text class=\"marker-label\" x=\"" << num(l.x) << "\" y=\"" << num(l.y) << "\" fill=\""
      << l.colour << "\">" << html_escape(l.text) << "</text>\n";
  }
  double ly = kTop + kPlotHeight + 60;
  for (std::size_t i = 0; i < curves.size(); ++i) {
    s << "<line x1=\"" << kLeft << "\" x2=\"" << num(kLeft + 16) << "\" y1=\"" << num(ly - 4)
      << "\" y2=\"" << num(ly - 4) << "\" stroke=\"" << curve_colour(i) << "\" stroke-width=\"3\""
      << dashes[i] << "/><text class=\"legend\" x=\"" << num(kLeft + 22) << "\" y=\"" << num(ly)
      << "\">"
      << html_escape(legend_label(curves[i].label + " — from the " + curves[i].source, 100))
      << "<title>" << html_escape(curves[i].label + " — from the " + curves[i].source)
      << "</title></text>\n";
    ly += 18;
  }
  s << "</svg>\n";
  return s.str();
}

std::string trend_svg(const HistorySeries& series, const std::string& benchmark) {
  // Runs left to right, oldest first, evenly spaced (a run's place, not its date: runs come in
  // bursts); the value axis from 0, so that a step reads at its true size.
  constexpr double kWidth = 760, kLeft = 60, kRight = 24, kTop = 40, kPlot = 150;
  const auto& points = series.points;
  if (points.empty()) return "";
  double top = 0;
  for (const auto& p : points) {
    for (double v : {p.value, p.high}) {
      if (std::isfinite(v)) top = std::max(top, v);
    }
  }
  if (!(top > 0)) return "";
  const double step = nice_step(top, 4);
  top = std::ceil(top / step) * step;
  const double span = kWidth - kLeft - kRight;
  auto px = [&](std::size_t i) {
    return points.size() == 1
               ? kLeft + span / 2
               : kLeft + span * static_cast<double>(i) / static_cast<double>(points.size() - 1);
  };
  auto py = [&](double v) { return kTop + kPlot * (1 - std::max(v, 0.0) / top); };
  const double height = kTop + kPlot + 62;
  std::ostringstream s;
  s << "<svg class=\"trend\" data-benchmark=\"" << html_escape(benchmark) << "\" data-series=\""
    << html_escape(series.name) << "\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << kWidth
    << "\" height=\"" << num(height) << "\" viewBox=\"0 0 " << kWidth << " " << num(height)
    << "\" role=\"img\">\n<title>"
    << html_escape(benchmark + ": latency p50 run after run, " + series.name) << "</title>\n";
  s << "<text class=\"plot-title\" x=\"8\" y=\"18\">"
    << html_escape(legend_label(benchmark + ": p50 latency run after run — " + series.name, 110))
    << "</text>\n";
  for (int k = 0; k <= static_cast<int>(std::lround(top / step)); ++k) {
    const double y = py(k * step);
    s << "<line x1=\"" << kLeft << "\" x2=\"" << num(kWidth - kRight) << "\" y1=\"" << num(y)
      << "\" y2=\"" << num(y) << "\" stroke=\"#e4e4e4\"/><text class=\"tick\" x=\""
      << num(kLeft - 6) << "\" y=\"" << num(y + 4) << "\" text-anchor=\"end\">"
      << format_value(k * step) << "</text>\n";
  }
  // Change points: a dashed line between the last run of a level and the first of the next,
  // with the size of the step.
  for (const auto& c : series.changes) {
    const double x = (px(c.index - 1) + px(c.index)) / 2;
    char change[48];
    std::snprintf(change, sizeof change, "%+.1f %%", c.change_percent());
    s << "<g class=\"change-point\"><line x1=\"" << num(x) << "\" x2=\"" << num(x) << "\" y1=\""
      << num(kTop - 8) << "\" y2=\"" << num(kTop + kPlot) << "\" stroke=\"#d55e00\" "
      << "stroke-dasharray=\"5 3\" stroke-width=\"1.5\"/><text class=\"tick\" x=\"" << num(x + 4)
      << "\" y=\"" << num(kTop - 2) << "\" fill=\"#d55e00\">" << change << "<title>change point "
      << "(E-divisive means, p = " << c.p_value << "): " << format_value(c.before) << " -> "
      << format_value(c.after) << " ms</title></text></g>\n";
  }
  std::string line;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!std::isfinite(points[i].value)) continue;
    line += (line.empty() ? "M" : "L") + num(px(i)) + " " + num(py(points[i].value));
  }
  s << "<path class=\"trend-line\" d=\"" << line << "\" stroke=\"#0072b2\" fill=\"none\" "
    << "stroke-width=\"1.5\"/>\n";
  // Revision labels under the axis, as many as fit side by side, evenly chosen: a git hash by its
  // first 7 digits, other labels shortened to 10 characters.
  std::vector<std::string> labels;
  std::size_t widest = 1;
  for (const auto& p : points) {
    const std::string revision = short_revision(p.revision, 7);
    labels.push_back(revision == p.revision ? legend_label(p.revision, 10) : revision);
    widest = std::max(widest, labels.back().size());
  }
  const auto fit = std::max<std::size_t>(
      1, static_cast<std::size_t>(span / (static_cast<double>(widest) * kLabelCharWidth + 12)));
  const std::size_t every = (points.size() + fit - 1) / fit;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto& p = points[i];
    const double x = px(i);
    if (std::isfinite(p.low) && std::isfinite(p.high)) {
      s << "<path class=\"whisker\" d=\"M" << num(x) << " " << num(py(p.low)) << "V"
        << num(py(p.high)) << "\" stroke=\"#222\" fill=\"none\"/>\n";
    }
    s << "<circle class=\"point\" cx=\"" << num(x) << "\" cy=\"" << num(py(p.value))
      << "\" r=\"3.5\" fill=\"#0072b2\" stroke=\"#fff\"><title>" << html_escape(p.revision) << ", "
      << html_escape(p.started_utc) << ": " << format_value(p.value) << " ms";
    if (std::isfinite(p.low) && std::isfinite(p.high))
      s << " (" << format_value(p.low) << " .. " << format_value(p.high) << ")";
    s << ", " << p.runs << (p.runs == 1 ? " run" : " runs") << "</title></circle>\n";
    if (i % every == 0) {
      s << "<text class=\"tick\" x=\"" << num(x) << "\" y=\"" << num(kTop + kPlot + 16)
        << "\" text-anchor=\"middle\">" << html_escape(labels[i]) << "</text>\n";
    }
  }
  s << "<line x1=\"" << kLeft << "\" x2=\"" << num(kWidth - kRight) << "\" y1=\""
    << num(kTop + kPlot) << "\" y2=\"" << num(kTop + kPlot) << "\" stroke=\"#666\"/>\n"
    << "<text class=\"axis-label\" x=\"" << num(kLeft + span / 2) << "\" y=\""
    << num(kTop + kPlot + 40)
    << "\" text-anchor=\"middle\">runs, oldest first (their revisions); p50 latency (ms) with "
       "its 95 % interval</text>\n</svg>\n";
  return s.str();
}

}  // namespace robotperf::report::detail
