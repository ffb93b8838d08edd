#include <algorithm>
#include <cmath>
#include <sstream>

#include "report_model.hpp"
#include "robotperf/report/readme.hpp"

namespace robotperf::report {
namespace {

using detail::html_escape;
using detail::Table;

constexpr const char* kStyle = R"(
body { font-family: "DejaVu Sans", Helvetica, Arial, sans-serif; margin: 24px; color: #222;
       max-width: 1600px; }
h1 { margin-bottom: 4px; } h2 { border-bottom: 2px solid #444; padding-bottom: 4px;
       margin-top: 36px; } h3 { margin-top: 28px; }
p.summary { color: #555; margin-top: 0; }
table { border-collapse: collapse; margin: 8px 0 16px; font-size: 13px; }
th, td { border: 1px solid #ccc; padding: 3px 7px; vertical-align: top; }
th { background: #eef3f8; text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
tr.warn td { background: #fff1e6; }
div.warnings { background: #fff6e0; border-left: 5px solid #e69500; padding: 8px 16px; }
div.warnings li { margin: 3px 0; }
div.warnings ul.invalid li { color: #a00000; font-weight: bold; }
span.difference { color: #a05000; }
div.warnings details p { margin: 6px 0 0 0; }
div.radars { display: flex; flex-wrap: wrap; gap: 12px; }
figure { margin: 0; } figcaption { font-size: 12px; color: #555; max-width: 760px; }
svg text { font-family: "DejaVu Sans", Helvetica, Arial, sans-serif; }
svg .plot-title { font-size: 13px; font-weight: bold; } svg .axis-label { font-size: 12px; }
svg .axis-scale, svg .tick, svg .legend, svg .marker-label { font-size: 11px; fill: #444; }
p.note { font-size: 12px; color: #555; }
section.summary { background: #f6f8fa; border: 1px solid #d8dee4; padding: 4px 18px 12px; }
ul.findings li { margin: 4px 0; }
details.filters { border-bottom: 1px solid #ccc; padding: 6px 0; margin-top: 12px;
                  font-size: 13px; }
details.filters summary { font-size: 14px; }
details.filters fieldset { display: inline-block; border: 1px solid #ccc; margin: 2px 6px 2px 0;
                       padding: 2px 8px; vertical-align: top; max-width: 100%; }
details.filters label { margin-right: 10px; white-space: nowrap; }
ul.key { list-style: none; padding: 0; display: flex; flex-wrap: wrap; gap: 4px 18px;
         font-size: 13px; }
span.swatch { display: inline-block; width: 14px; height: 10px; margin-right: 6px;
              border: 2px solid; vertical-align: middle; }
span.swatch.published { background: repeating-linear-gradient(45deg, #fff 0 2px, #666 2px 4px); }
.filtered { display: none; }
)";

// Hides the rows and bars that an unticked filter value tags, and closes the gaps in the bar
// charts. No network, no library: the page stays one file.
constexpr const char* kFilterScript = R"(<script>
(() => {
  const boxes = Array.from(document.querySelectorAll('#filters input[type=checkbox]'));
  const status = document.getElementById('filter-status');
  function apply() {
    const off = {};
    for (const box of boxes) {
      if (!box.checked) (off[box.dataset.group] = off[box.dataset.group] || new Set()).add(box.value);
    }
    let shown = 0, all = 0;
    document.querySelectorAll('[data-source]').forEach(element => {
      const hide = Object.keys(off).some(group => {
        const value = element.getAttribute('data-' + group);
        return value !== null && off[group].has(value);
      });
      element.classList.toggle('filtered', hide);
      if (element.classList.contains('bar-row')) {
        ++all;
        shown += !hide;
      }
    });
    document.querySelectorAll('svg.barchart').forEach(svg => {
      const row = Number(svg.dataset.row);
      let y = Number(svg.dataset.top);
      svg.querySelectorAll('g.bar-row').forEach(g => {
        if (g.classList.contains('filtered')) return;
        g.setAttribute('transform', 'translate(0,' + y + ')');
        y += row;
      });
      svg.querySelector('g.axis').setAttribute('transform', 'translate(0,' + (y + 4) + ')');
      const width = svg.viewBox.baseVal.width;
      svg.setAttribute('height', y + 48);
      svg.setAttribute('viewBox', '0 0 ' + width + ' ' + (y + 48));
    });
    status.textContent = 'showing ' + shown + ' of ' + all + ' bars';
  }
  boxes.forEach(box => box.addEventListener('change', apply));
  apply();
})();
</script>
)";

std::string table_html(const Table& t) {
  std::ostringstream s;
  s << "<table class=\"" << t.css_class << "\">\n<thead><tr>";
  for (const auto& h : t.header) s << "<th>" << html_escape(h) << "</th>";
  s << "</tr></thead>\n<tbody>\n";
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    s << "<tr" << (r < t.row_warning.size() && t.row_warning[r] ? " class=\"warn\"" : "");
    if (r < t.row_tags.size()) {
      for (const auto& [group, value] : t.row_tags[r])
        s << " data-" << group << "=\"" << html_escape(value) << "\"";
    }
    s << ">";
    for (std::size_t c = 0; c < t.rows[r].size(); ++c) {
      s << "<td" << (c < t.numeric.size() && t.numeric[c] ? " class=\"num\"" : "") << ">"
        << html_escape(t.rows[r][c]) << "</td>";
    }
    s << "</tr>\n";
  }
  s << "</tbody></table>\n";
  return s.str();
}

// The numbers behind a bar chart, for the page's folded table and the Markdown file.
Table chart_table(const detail::BarChart& chart) {
  Table t;
  t.css_class = "chart-data";
  t.header = {"configuration", chart.figure + " latency ms", "95 % interval", "from", "source"};
  t.numeric = {false, true, true, true, false};
  for (const auto& b : chart.bars) {
    const bool interval = std::isfinite(b.lower) && std::isfinite(b.upper);
    t.rows.push_back(
        {b.series, detail::format_value(b.value),
         interval ? detail::format_value(b.lower) + " – " + detail::format_value(b.upper) : "-",
         b.count, b.local ? "local runs" : "published RobotPerf"});
    t.row_warning.push_back(false);
    t.row_tags.push_back(b.tags);
  }
  return t;
}

std::string chart_caption(const detail::BarChart& chart) {
  return chart.axis +
         ". Solid: local runs; hatched: published RobotPerf rows that pass the measurement rules. "
         "Whiskers: the 95 % interval where known (one run: of its p50; six or more runs or rows: "
         "of their median); dots: each run of a configuration that ran more than once.";
}

// Whether any bar of the page is published rows drawn without a colour of their own.
bool published_bars(const detail::Model& m) {
  for (const auto& [category, sections] : m.benchmarks) {
    for (const auto& section : sections) {
      for (const auto& chart : section.charts) {
        if (std::ranges::any_of(chart.bars, [](const detail::Bar& b) {
              return !b.local && b.colour == detail::kNoColour;
            }))
          return true;
      }
    }
  }
  return false;
}

constexpr const char* kSignificanceNote =
    "Significance: with six or more runs per side, the medians' distribution-free 95 % "
    "intervals; with two to five, Welch's t-test at the 5 % level over the per-run values; with "
    "one run per side only the mean latency is judged, from the spread within the runs.";

// The summary section: what ran, the findings, the table per benchmark, validity.
void write_summary(std::ostream& s, const detail::Model& m) {
  s << "<section class=\"summary\" id=\"summary\">\n<h2>Summary</h2>\n";
  for (const auto& line : m.overview) s << "<p>" << html_escape(line) << "</p>\n";
  if (!m.findings.empty()) {
    s << "<ul class=\"findings\">\n";
    for (const auto& f : m.findings) s << "<li>" << html_escape(f) << "</li>\n";
    s << "</ul>\n";
  }
  if (!m.at_a_glance.rows.empty()) s << table_html(m.at_a_glance);
  if (const std::string summary = detail::warning_summary(m); !summary.empty()) {
    // INVALID runs in view; the warnings behind one line, grouped by machine and by run.
    s << "<div class=\"warnings\" id=\"warnings\"><strong>Validity:</strong> "
      << html_escape(summary) << "\n";
    if (!m.invalid_runs.empty()) {
      s << "<ul class=\"invalid\">\n";
      for (const auto& w : m.invalid_runs) s << "<li>" << html_escape(w) << "</li>\n";
      s << "</ul>\n";
    }
    std::vector<detail::WarningGroup> groups = m.warning_groups;
    if (!m.warnings.empty()) groups.push_back({"this report", m.warnings});
    if (!groups.empty()) {
      s << "<details><summary>the warnings, by machine and by run</summary>\n";
      for (const auto& g : groups) {
        s << "<p><strong>" << html_escape(g.heading) << "</strong></p><ul>\n";
        for (const auto& w : g.items) s << "<li>" << html_escape(w) << "</li>\n";
        s << "</ul>\n";
      }
      s << "</details>\n";
    }
    s << "</div>\n";
  }
  s << "</section>\n";
}

// The folded filters and the page's one key of colours.
void write_filters_and_key(std::ostream& s, const detail::Model& m) {
  if (!m.filters.empty()) {
    // Folded: the page reads whole first; a reader narrows it on purpose.
    std::vector<std::string> groups;
    for (const auto& [group, values] : m.filters) groups.push_back(group);
    s << "<details class=\"filters\" id=\"filters\"><summary><strong>Filter</strong> by "
      << html_escape(joined(groups, ", ")) << " — <span id=\"filter-status\"></span></summary>\n";
    for (const auto& [group, values] : m.filters) {
      s << "<fieldset><legend>" << html_escape(group) << "</legend>";
      for (const auto& v : values) {
        s << "<label><input type=\"checkbox\" checked data-group=\"" << html_escape(group)
          << "\" value=\"" << html_escape(v) << "\">" << html_escape(v) << "</label>";
      }
      s << "</fieldset>\n";
    }
    s << "</details>\n";
  }
  if (!m.key.empty()) {
    // The page's one legend of colours: each series keeps its colour on every plot.
    s << "<ul class=\"key\" id=\"series-key\">\n";
    for (const auto& k : m.key) {
      const bool coloured = k.colour != detail::kNoColour;
      const char* colour = detail::colour_of(k.colour);
      s << "<li data-series=\"" << html_escape(k.series) << "\" data-colour=\""
        << (coloured ? colour : "none") << "\"><span class=\"swatch"
        << (k.local ? "" : " published") << "\" style=\"border-color: " << colour
        << (k.local ? std::string("; background: ") + (coloured ? colour : "#fff") : "")
        << "\"></span>" << html_escape(k.series) << "</li>\n";
    }
    if (published_bars(m)) {
      s << "<li class=\"published-key\"><span class=\"swatch published\" style=\"border-color: "
           "#333\"></span>published RobotPerf rows: hatched, each named beside its bar</li>\n";
    }
    s << "</ul>\n";
  }
}

// A category's radars (report --radar) and the values behind them.
void write_radars(std::ostream& s, const detail::Model& m, const std::string& category) {
  const bool radars = !m.radars.at(category).empty();  // asked for with --radar
  if (radars) s << "<div class=\"radars\">\n";
  for (const auto& radar : m.radars.at(category)) {
    s << "<figure>\n";
    if (radar.axes.empty()) {
      s << "<p class=\"note\">No " << radar.metric << " figures in " << html_escape(category)
        << (radar.metric == "power" ? " (power is reported only where a real sensor was read)" : "")
        << ".</p>\n";
    } else {
      s << detail::radar_svg(radar);
      s << (detail::drawn_as_bars(radar)
                ? "<figcaption>One group of bars per benchmark, each on its own scale from 0 "
                  "(fewer than three benchmarks, or one value per benchmark, make no radar); "
                  "one bar per series (solid: "
                  "local runs, median of valid runs; pale and dashed: published RobotPerf rows, "
                  "median of the rows that pass the measurement rules)."
                : "<figcaption>Each axis is one benchmark with its own scale (written at its "
                  "end; logarithmic where that axis's values span more than 20x, else linear "
                  "from 0); one polygon per series "
                  "(solid: local runs, median of valid runs; dashed: published RobotPerf rows, "
                  "median of the rows that pass the measurement rules).");
      if (radar.metric == "throughput") {
        s << " A series named “· peak” is the peak --find-peak found; the others are "
             "the output rate at the rate they were fed, a lower bound on what they sustain.";
      }
      for (const auto& note : radar.notes) {
        s << "<br><span class=\"difference\">Not alike: " << html_escape(note) << "</span>";
      }
      s << "</figcaption>\n";
    }
    s << "</figure>\n";
  }
  if (radars) s << "</div>\n";
  for (const auto& radar : m.radars.at(category)) {
    if (radar.axes.empty()) continue;
    s << "<details><summary>" << html_escape(radar.metric) << " values behind the plot</summary>\n"
      << table_html(radar.data) << "</details>\n";
  }
}

// What a trend shows, in words: its runs and each change point, or that there is none.
std::string trend_caption(const HistorySeries& trend) {
  std::size_t runs = 0;
  for (const auto& p : trend.points) runs += p.runs;
  std::string text = std::to_string(runs) + " runs of " + trend.name + ". ";
  if (trend.changes.empty()) return text + "No change point: one level throughout.";
  for (const auto& c : trend.changes) {
    char line[160];
    std::snprintf(line, sizeof line, "From run %zu (%s): %s -> %s ms, %+.1f %% (p = %.3g). ",
                  c.index + 1, short_revision(trend.points[c.index].revision, 10).c_str(),
                  detail::format_value(c.before).c_str(), detail::format_value(c.after).c_str(),
                  c.change_percent(), c.p_value);
    text += line;
  }
  return text + "Change points by E-divisive means.";
}

// One benchmark: its bar charts, the table against the published rows, its runs and what else
// they measured, and the published rows.
void write_benchmark(std::ostream& s, const detail::BenchmarkSection& b) {
  s << "<h3 id=\"benchmark-" << html_escape(b.id) << "\">" << html_escape(b.id) << " — "
    << html_escape(b.name) << "</h3>\n";
  for (const auto& chart : b.charts) {
    s << "<figure>\n"
      << detail::bar_chart_svg(chart) << "<figcaption>" << html_escape(chart_caption(chart));
    for (const auto& note : chart.notes) {
      s << "<br><span class=\"difference\">Not alike: " << html_escape(note) << "</span>";
    }
    s << "</figcaption>\n</figure>\n<details><summary>" << html_escape(chart.figure)
      << " latency values behind the plot</summary>\n"
      << table_html(chart_table(chart)) << "</details>\n";
  }
  if (!b.versus_published.rows.empty()) {
    s << "<p class=\"note\">This system against the published RobotPerf rows measured alike "
         "(black-box latency rows that pass the measurement rules and state the configuration's "
         "rate; maximum latency on both sides; each system by the median of its rows):</p>\n"
      << table_html(b.versus_published);
  }
  if (!b.runs.rows.empty()) {
    s << table_html(b.runs);
    if (!b.also_measured.rows.empty()) {
      s << "<p class=\"note\">What the runs also measured:</p>\n" << table_html(b.also_measured);
    }
    if (!b.outputs.rows.empty()) {
      s << "<p class=\"note\">Each monitored output, with its output jitter (|interval between "
           "consecutive outputs - the input period|):</p>\n"
        << table_html(b.outputs);
    }
    if (!b.hops.rows.empty()) {
      s << "<p class=\"note\">Where the time goes (grey-box, per hop):</p>\n"
        << detail::hops_svg(b.hop_bars, b.hops_run) << table_html(b.hops);
    }
    if (!b.callbacks.rows.empty()) {
      s << "<p class=\"note\">Callback durations (grey-box):</p>\n" << table_html(b.callbacks);
    }
    if (!b.peak_search.rows.empty()) {
      s << "<p class=\"note\">Peak search (--find-peak), step by step:</p>\n"
        << table_html(b.peak_search);
    }
    if (!b.distribution.empty()) s << detail::distribution_svg(b.distribution, b.id);
    for (const auto& trend : b.trends) {
      s << "<figure>\n"
        << detail::trend_svg(trend, b.id) << "<figcaption>" << html_escape(trend_caption(trend))
        << "</figcaption>\n</figure>\n";
    }
  } else {
    s << "<p class=\"note\">No local runs of " << html_escape(b.id) << ".</p>\n";
  }
  if (!b.published.rows.empty()) {
    s << "<p class=\"note\">Published RobotPerf results: " << b.published_rows
      << " rows; medians over the rows that pass the measurement rules.</p>\n"
      << table_html(b.published);
  }
  if (!b.flagged.rows.empty()) {
    s << "<details><summary>" << b.flagged.rows.size()
      << " published rows break the measurement rules</summary>\n"
      << table_html(b.flagged) << "</details>\n";
  }
}

// The comparison (or why there is none) and the machines.
void write_comparison_and_machines(std::ostream& s, const detail::Model& m) {
  if (m.comparison) {
    s << "<h2 id=\"comparison\">Comparison</h2>\n<p>A = <strong>" << html_escape(m.comparison->a)
      << "</strong>, B = <strong>" << html_escape(m.comparison->b) << "</strong>.</p>\n"
      << table_html(m.comparison->table) << "<p class=\"note\">";
    for (const auto& n : m.comparison->notes) s << html_escape(n) << "<br>";
    s << html_escape(kSignificanceNote) << "</p>\n";
  } else if (!m.no_comparison.empty()) {
    s << "<h2 id=\"comparison\">Comparison</h2>\n<p class=\"note\">" << html_escape(m.no_comparison)
      << "</p>\n";
  }
  if (!m.machines.rows.empty()) {
    s << "<h2 id=\"machines\">Machines</h2>\n" << table_html(m.machines);
  }
}

}  // namespace

std::string render_comparison_text(const ReportInput& input, const std::string& a,
                                   const std::string& b) {
  const detail::Comparison c = detail::build_comparison(input, a, b);
  std::ostringstream s;
  s << "A = " << a << "\nB = " << b << "\n\n" << table_text(c.table) << "\n";
  for (const auto& n : c.notes) s << n << "\n";
  s << kSignificanceNote << "\n";
  return s.str();
}

std::string render_html(const ReportInput& input, const ReportOptions& options) {
  const detail::Model m = detail::build_model(input, options);
  std::ostringstream s;
  s << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
    << "<meta name=\"generator\" content=\"robotperf\">\n<title>" << html_escape(m.title)
    << "</title>\n<style>" << kStyle << "</style>\n</head>\n<body>\n";
  s << "<h1>" << html_escape(m.title) << "</h1>\n<p class=\"summary\">" << html_escape(m.summary)
    << "</p>\n";
  write_summary(s, m);
  write_filters_and_key(s, m);
  for (const auto& category : m.categories) {
    s << "<h2 id=\"category-" << html_escape(category) << "\">" << html_escape(category)
      << "</h2>\n";
    write_radars(s, m, category);
    for (const auto& b : m.benchmarks.at(category)) write_benchmark(s, b);
  }
  write_comparison_and_machines(s, m);
  s << "<p class=\"note\">Latency is measured from the scheduled send time (immune to "
       "coordinated omission); the RobotPerf headline latency is its maximum. Throughput is the "
       "output rate; power is the average over the measured window, reported only when a real "
       "sensor was read.</p>\n";
  if (!m.filters.empty()) s << kFilterScript;  // it drives the filters, when there are any
  s << "</body>\n</html>\n";
  return s.str();
}

std::string render_markdown(const ReportInput& input, const ReportOptions& options) {
  const detail::Model m = detail::build_model(input, options);
  std::ostringstream s;
  auto table = [&](const Table& t) {
    s << "|";
    for (const auto& h : t.header) s << " " << markdown_cell(h) << " |";
    s << "\n|";
    for (std::size_t c = 0; c < t.header.size(); ++c)
      s << (c < t.numeric.size() && t.numeric[c] ? "---:|" : "---|");
    s << "\n";
    for (std::size_t r = 0; r < t.rows.size(); ++r) {
      s << "|";
      for (std::size_t c = 0; c < t.rows[r].size(); ++c) {
        const bool warn = c == 0 && r < t.row_warning.size() && t.row_warning[r];
        s << " " << (warn ? "⚠ " : "") << markdown_cell(t.rows[r][c]) << " |";
      }
      s << "\n";
    }
    s << "\n";
  };
  s << "# " << m.title << "\n\n" << m.summary << "\n\n## Summary\n\n";
  for (const auto& line : m.overview) s << line << "\n\n";
  for (const auto& f : m.findings) s << "- " << markdown_cell(f) << "\n";
  if (!m.findings.empty()) s << "\n";
  if (!m.at_a_glance.rows.empty()) table(m.at_a_glance);
  if (const std::string summary = detail::warning_summary(m); !summary.empty()) {
    s << "## Validity\n\n" << summary << "\n\n";
    for (const auto& w : m.invalid_runs) s << "- " << markdown_cell(w) << "\n";
    if (!m.invalid_runs.empty()) s << "\n";
    std::vector<detail::WarningGroup> groups = m.warning_groups;
    if (!m.warnings.empty()) groups.push_back({"this report", m.warnings});
    for (const auto& g : groups) {
      s << "### " << g.heading << "\n\n";
      for (const auto& w : g.items) s << "- " << markdown_cell(w) << "\n";
      s << "\n";
    }
  }
  for (const auto& category : m.categories) {
    s << "## " << category << "\n\n";
    for (const auto& radar : m.radars.at(category)) {
      if (radar.axes.empty()) continue;
      s << "**" << radar.figure << " (" << radar.unit << "), "
        << (radar.smaller_is_better ? "smaller" : "larger")
        << " is better** — the values of the radar plot\n\n";
      for (const auto& note : radar.notes) s << "Not alike: " << markdown_cell(note) << "\n\n";
      table(radar.data);
    }
    for (const auto& b : m.benchmarks.at(category)) {
      s << "### " << b.id << " — " << b.name << "\n\n";
      for (const auto& chart : b.charts) {
        s << "**" << chart.axis << "**\n\n";
        for (const auto& note : chart.notes) s << "Not alike: " << markdown_cell(note) << "\n\n";
        table(chart_table(chart));
      }
      if (!b.versus_published.rows.empty()) {
        s << "Against the published RobotPerf rows measured alike (black-box, same rate, maximum "
             "latency):\n\n";
        table(b.versus_published);
      }
      if (!b.runs.rows.empty()) table(b.runs);
      if (!b.also_measured.rows.empty()) {
        s << "What the runs also measured:\n\n";
        table(b.also_measured);
      }
      if (!b.outputs.rows.empty()) {
        s << "Each monitored output, with its output jitter (|interval between consecutive "
             "outputs - the input period|):\n\n";
        table(b.outputs);
      }
      if (!b.hops.rows.empty()) {
        s << "Where the time goes (grey-box, per hop):\n\n";
        table(b.hops);
      }
      if (!b.callbacks.rows.empty()) {
        s << "Callback durations (grey-box):\n\n";
        table(b.callbacks);
      }
      if (!b.peak_search.rows.empty()) {
        s << "Peak search (--find-peak), step by step:\n\n";
        table(b.peak_search);
      }
      if (!b.published.rows.empty()) {
        s << "Published RobotPerf results (" << b.published_rows
          << " rows; medians over the rows that pass the measurement rules):\n\n";
        table(b.published);
      }
      if (!b.flagged.rows.empty()) {
        s << "Published rows that break the measurement rules:\n\n";
        table(b.flagged);
      }
    }
  }
  if (m.comparison) {
    s << "## Comparison\n\nA = **" << markdown_cell(m.comparison->a) << "**, B = **"
      << markdown_cell(m.comparison->b) << "**\n\n";
    table(m.comparison->table);
    for (const auto& n : m.comparison->notes) s << "- " << markdown_cell(n) << "\n";
    s << "\n" << kSignificanceNote << "\n\n";
  } else if (!m.no_comparison.empty()) {
    s << "## Comparison\n\n" << m.no_comparison << "\n\n";
  }
  if (!m.machines.rows.empty()) {
    s << "## Machines\n\n";
    table(m.machines);
  }
  return s.str();
}

}  // namespace robotperf::report
