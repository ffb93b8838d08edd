#include "report_model.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <tuple>
#include <utility>

#include "robotperf/build_info.hpp"
#include "robotperf/metrics/latency_stats.hpp"
#include "robotperf/report/significance.hpp"
#include "robotperf/report/standing.hpp"

namespace robotperf::report {
namespace {

namespace fs = std::filesystem;
using detail::Table;

std::string lower(std::string s) {
  std::ranges::transform(s, s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

double median(std::vector<double> v) {
  std::erase_if(v, [](double x) { return !std::isfinite(x); });
  return metrics::median(std::move(v));  // NaN (kNoValue) for none
}

// A value of one metric measured once: by a local run or in a published row.
struct Observation {
  std::string benchmark_id, category, series, metric;
  bool local = false;
  double value = kNoValue;
  const StoredRun* run = nullptr;
  std::string type;  // black | grey: how it was measured
  std::string rate;  // the rate it was measured at ("30 Hz", "peak search"), "" when unknown
};

// The rate a local run was measured at, as published rows state theirs: a control benchmark's is
// its controller loop's.
std::string rate_text(const StoredRun& r) {
  if (r.throughput_kind == "peak") return "peak search";
  const double hz = r.update_rate_hz.value_or(r.rate_hz);
  if (!std::isfinite(hz)) return "";
  char text[32];
  std::snprintf(text, sizeof text, "%g Hz", hz);
  return text;
}

struct MetricInfo {
  const char* metric;
  const char* unit;
  bool smaller_is_better;
  const char* figure;  // what a plot's title calls it: the latency radars plot the maximum
};
constexpr MetricInfo kRadarMetrics[] = {{"latency", "ms", true, "maximum latency"},
                                        {"throughput", "fps", false, "throughput"},
                                        {"power", "W", true, "power"}};

std::vector<Observation> observations(const ReportInput& in) {
  std::vector<Observation> out;
  // A graph's throughput is its peak where a search found one; a run at a rate it kept up with
  // only says it can do at least that. The two are never pooled, and the series says which.
  // A peak is a property of the configuration, whatever rate the search ended at; an offered
  // throughput is a claim about its rate.
  std::set<std::pair<std::string, std::string>> with_peak;
  for (const auto& r : in.runs) {
    if (r.valid && r.throughput_kind == "peak")
      with_peak.emplace(r.benchmark_id, detail::configuration_series(r));
  }
  for (const auto& r : in.runs) {
    if (!r.valid) continue;  // invalid runs are shown in the tables, never plotted
    const std::string series = detail::local_series(r);
    const std::string rate = rate_text(r);
    out.push_back(
        {r.benchmark_id, r.category, series, "latency", true, r.latency.max, &r, r.type, rate});
    if (r.throughput_kind == "peak" ||
        !with_peak.contains({r.benchmark_id, detail::configuration_series(r)})) {
      out.push_back({r.benchmark_id, r.category, series, "throughput", true, r.throughput_hz, &r,
                     r.type, rate});
    }
    if (r.power_w) {
      out.push_back(
          {r.benchmark_id, r.category, series, "power", true, *r.power_w, &r, r.type, rate});
    }
  }
  for (const auto& b : in.published) {
    for (const auto& row : b.results) {
      if (!row.flags.empty() || !std::isfinite(row.value)) continue;
      out.push_back({b.id, b.category, detail::published_series(row), row.metric, false, row.value,
                     nullptr, row.type, row.stated_rate()});
    }
  }
  return out;
}

// Where local runs and published rows share an axis but not a measurement, said next to the plot:
// another type (black- or grey-box), another stated rate, or medians so far apart (20x) that they
// cannot both measure the same thing (a control benchmark's latency that includes its loop's
// period).
std::vector<std::string> differences_on_axes(const std::string& category, const char* metric,
                                             const char* unit,
                                             const std::vector<Observation>& obs) {
  std::map<std::string, std::array<std::vector<double>, 2>> values;  // id -> [published, local]
  std::map<std::string, std::array<std::set<std::string>, 2>> types, rates;
  for (const auto& o : obs) {
    if (o.category != category || o.metric != metric) continue;
    values[o.benchmark_id][o.local].push_back(o.value);
    if (!o.type.empty()) types[o.benchmark_id][o.local].insert(o.type);
    if (!o.rate.empty()) rates[o.benchmark_id][o.local].insert(o.rate);
  }
  std::vector<std::string> notes;
  for (const auto& [id, v] : values) {
    if (v[0].empty() || v[1].empty()) continue;
    const auto& [published_types, local_types] = types[id];
    if (!published_types.empty() && !local_types.empty() && published_types != local_types) {
      notes.push_back(id + ": the published rows are " + joined(published_types, "/") +
                      "-box measurements, the local runs " + joined(local_types, "/") + "-box");
    }
    const auto& [published_rates, local_rates] = rates[id];
    if (!published_rates.empty() && !local_rates.empty() && published_rates != local_rates) {
      notes.push_back(id + ": the published rows state " + joined(published_rates, ", ") +
                      ", the local runs ran at " + joined(local_rates, ", ") +
                      " (--compare rate=HZ picks one)");
    }
    const double published = median(v[0]), local = median(v[1]);
    if (published > 0 && local > 0 && (local / published > 20 || published / local > 20)) {
      notes.push_back(id + ": local runs (median " + detail::format_value(local) + " " + unit +
                      ") and published rows (median " + detail::format_value(published) + " " +
                      unit + ") differ " +
                      detail::format_value(std::max(local / published, published / local)) +
                      "x: they are unlikely to measure the same thing (check what each includes, "
                      "e.g. a control loop's period)");
    }
  }
  return notes;
}

std::vector<detail::Radar> radars_for(const std::string& category,
                                      const std::vector<Observation>& obs,
                                      const ReportOptions& options) {
  std::vector<detail::Radar> out;
  for (const auto& m : kRadarMetrics) {
    detail::Radar radar;
    radar.category = category;
    radar.metric = m.metric;
    radar.figure = m.figure;
    radar.unit = m.unit;
    radar.smaller_is_better = m.smaller_is_better;
    std::set<std::string> axes;
    std::map<std::string, std::map<std::string, std::vector<double>>> by_series;
    std::map<std::string, bool> is_local;
    for (const auto& o : obs) {
      if (o.category != category || o.metric != m.metric) continue;
      axes.insert(o.benchmark_id);
      by_series[o.series][o.benchmark_id].push_back(o.value);
      is_local[o.series] = o.local;
    }
    if (axes.empty()) {
      out.push_back(std::move(radar));
      continue;
    }
    radar.axes.assign(axes.begin(), axes.end());
    radar.notes = differences_on_axes(category, m.metric, m.unit, obs);
    // Local series first, then the published ones that cover the most benchmarks.
    std::vector<std::string> names;
    for (const auto& [name, values] : by_series) names.push_back(name);
    std::ranges::stable_sort(names, [&](const std::string& a, const std::string& b) {
      if (is_local[a] != is_local[b]) return is_local[a];
      return by_series[a].size() > by_series[b].size();
    });
    auto medians = [&](const std::string& name) {
      std::vector<double> row;
      for (const auto& axis : radar.axes) {
        const auto it = by_series[name].find(axis);
        row.push_back(it == by_series[name].end() ? kNoValue : median(it->second));
      }
      return row;
    };
    const std::size_t shown = std::min(options.max_radar_series, kMaxRadarSeries);
    for (std::size_t i = 0; i < names.size(); ++i) {
      if (i >= shown) {
        radar.omitted.push_back(names[i]);
        continue;
      }
      radar.series.push_back(names[i]);
      radar.series_local.push_back(is_local[names[i]]);
      radar.values.push_back(medians(names[i]));
    }
    radar.data.css_class = "radar-data";
    radar.data.header = {"hardware"};
    radar.data.numeric = {false};
    for (const auto& a : radar.axes) {
      radar.data.header.push_back(a + " (" + m.unit + ")");
      radar.data.numeric.push_back(true);
    }
    // Every series, those left out of the plot too (the legend points here for them).
    for (std::size_t s = 0; s < radar.series.size() + radar.omitted.size(); ++s) {
      const bool plotted = s < radar.series.size();
      const std::string& name = plotted ? radar.series[s] : radar.omitted[s - radar.series.size()];
      std::vector<std::string> row = {plotted ? name : name + " (not plotted)"};
      for (double v : plotted ? radar.values[s] : medians(name))
        row.push_back(detail::format_value(v));
      radar.data.rows.push_back(std::move(row));
      radar.data.row_warning.push_back(false);
    }
    out.push_back(std::move(radar));
  }
  return out;
}

// What the page's filters match a local run or a published row by.
std::map<std::string, std::string> tags_of(const StoredRun& r) {
  std::map<std::string, std::string> tags = {{"system", r.hardware},
                                             {"transport", r.rmw},
                                             {"source", "local runs"},
                                             {"mode", r.type.empty() ? "black" : r.type}};
  // The user's labels, one filter each (label-KEY); robotperf's own are not a choice to make.
  for (const auto& [key, value] : r.labels) {
    if (!key.starts_with("robotperf.")) tags["label-" + key] = value;
  }
  return tags;
}

std::map<std::string, std::string> tags_of(const PublishedResult& row) {
  // A published row names no transport: the transport filter leaves it alone.
  return {{"system", row.hardware},
          {"source", "published RobotPerf"},
          {"mode", row.type.empty() ? "black" : row.type}};
}

std::vector<detail::Distribution> distributions(const std::vector<const StoredRun*>& runs,
                                                std::vector<std::string>& warnings) {
  std::vector<detail::Distribution> out;
  for (const StoredRun* r : runs) {
    detail::Distribution d;
    d.label = r->stem() + (r->valid ? "" : " (INVALID)");
    d.series = detail::local_series(*r);
    d.valid = r->valid;
    d.p50 = r->latency.p50;
    d.p99 = r->latency.p99;
    if (!std::isfinite(d.p50)) continue;
    bool done = false;
    if (r->csv_path) {
      try {
        std::vector<double> v = read_latency_csv(*r->csv_path);
        std::ranges::sort(v);
        if (!v.empty()) {
          const std::size_t n = std::min<std::size_t>(v.size(), 400);
          for (std::size_t i = 0; i < n; ++i) {
            const double q = n == 1 ? 1.0 : static_cast<double>(i) / static_cast<double>(n - 1);
            d.points.emplace_back(metrics::quantile_of_sorted(v, q), q);
          }
          d.source = "per-message CSV";
          done = true;
        }
      } catch (const ReportError& e) {
        warnings.push_back(std::string(e.what()) + " (the stored distribution is shown instead)");
      }
    }
    if (!done && r->histogram && r->histogram->total() > 0) {
      const auto& h = *r->histogram;
      const double total = static_cast<double>(h.total());
      double cumulative = static_cast<double>(h.nonpositive);
      d.points.emplace_back(h.counts.empty() ? 0.0 : h.lower_edge(0), cumulative / total);
      for (std::size_t i = 0; i < h.counts.size(); ++i) {
        cumulative += static_cast<double>(h.counts[i]);
        // The last bin ends at the observed maximum, not at its upper edge.
        const double x = i + 1 == h.counts.size() && std::isfinite(r->latency.max)
                             ? std::min(h.upper_edge(i), r->latency.max)
                             : h.upper_edge(i);
        d.points.emplace_back(x, cumulative / total);
      }
      d.source = "stored histogram";
      done = true;
    }
    if (!done) {
      const auto& l = r->latency;
      for (auto [x, y] : {std::pair{l.min, 0.0},
                          {l.p50, 0.5},
                          {l.p90, 0.9},
                          {l.p99, 0.99},
                          {l.p999, 0.999},
                          {l.max, 1.0}}) {
        if (std::isfinite(x)) d.points.emplace_back(x, y);
      }
      d.source = "stored percentiles";
    }
    out.push_back(std::move(d));
  }
  return out;
}

Table runs_table_for(const std::vector<const StoredRun*>& runs) {
  Table t;
  t.css_class = "runs";
  // The configuration as every plot and legend of the page names it: which bar a run is in.
  t.header = {"run",     "configuration", "rate Hz", "matched", "loss %",         "min ms",
              "mean ms", "p50 ms",        "p99 ms",  "max ms",  "throughput fps", "power W",
              "validity"};
  t.numeric = {false, false, true, true, true, true, true, true, true, true, true, true, false};
  for (const StoredRun* r : runs) {
    std::string validity = r->valid ? "valid" : "INVALID";
    for (std::size_t i = 0; i < r->invalid_reasons.size(); ++i)
      validity += (i ? "; " : ": ") + r->invalid_reasons[i];
    t.rows.push_back({r->stem(), detail::local_series(*r), format_fixed(r->rate_hz, 1),
                      std::to_string(r->matched) + "/" + std::to_string(r->measured),
                      format_fixed(r->loss_percent, 2), format_fixed(r->latency.min, 3),
                      format_fixed(r->latency.mean, 3), format_fixed(r->latency.p50, 3),
                      format_fixed(r->latency.p99, 3), format_fixed(r->latency.max, 3),
                      format_fixed(r->throughput_hz, 2),
                      r->power_w ? format_fixed(*r->power_w, 2) : "-", validity});
    t.row_warning.push_back(!r->valid);
    t.row_tags.push_back(tags_of(*r));
  }
  return t;
}

// What else each run measured, as its terminal summary shows it; empty when no run has any of it.
Table also_measured_table_for(const std::vector<const StoredRun*>& runs) {
  Table t;
  t.css_class = "also-measured";
  t.header = {"run",          "functional check",  "CPU % (graph)",
              "peak RSS MiB", "energy mJ/message", "control loop"};
  t.numeric = {false, false, true, true, true, false};
  bool any = false;
  for (const StoredRun* r : runs) {
    const bool energy = r->energy_j && r->matched > 0;
    any = any || !r->functional.empty() || r->cpu_percent || energy || !r->control.empty();
    t.rows.push_back(
        {r->stem(), r->functional.empty() ? "not checked" : r->functional,
         r->cpu_percent ? format_fixed(*r->cpu_percent, 1) : "-",
         r->peak_rss_mib ? format_fixed(*r->peak_rss_mib, 1) : "-",
         energy ? format_fixed(*r->energy_j * 1e3 / static_cast<double>(r->matched), 3) : "-",
         r->control.empty() ? "-" : r->control});
    t.row_warning.push_back(r->functional.starts_with("INVALID"));
  }
  if (!any) t.rows.clear();
  return t;
}

// Each run's monitored outputs (graph.yaml `outputs:`, or its one output) with their latency, rate
// and output jitter; empty when no run recorded its outputs.
Table outputs_table_for(const std::vector<const StoredRun*>& runs) {
  Table t;
  t.css_class = "outputs";
  t.header = {"run",    "output",  "loss %",         "p50 ms",        "p99 ms",
              "max ms", "out fps", "jitter mean ms", "jitter p99 ms", "input period ms"};
  t.numeric = {false, false, true, true, true, true, true, true, true, true};
  for (const StoredRun* r : runs) {
    for (const StoredOutput& o : r->outputs) {
      t.rows.push_back({r->stem(), o.topic, format_fixed(o.loss_percent, 2),
                        format_fixed(o.latency.p50, 3), format_fixed(o.latency.p99, 3),
                        format_fixed(o.latency.max, 3), format_fixed(o.throughput_hz, 2),
                        format_fixed(o.jitter.mean, 3), format_fixed(o.jitter.p99, 3),
                        format_fixed(o.period_ms, 3)});
      t.row_warning.push_back(o.loss_percent > 0);
    }
  }
  return t;
}

// The newest of `runs` that `has`, or null.
template <class Has>
const StoredRun* newest_where(const std::vector<const StoredRun*>& runs, Has has) {
  for (auto it = runs.rbegin(); it != runs.rend(); ++it) {
    if (has(**it)) return *it;
  }
  return nullptr;
}

// The newest grey-box run's per-hop breakdown: where the time of a message goes.
Table hops_table_for(const std::vector<const StoredRun*>& runs) {
  Table t;
  t.css_class = "hops";
  const StoredRun* r = newest_where(runs, [](const StoredRun& x) { return !x.hops.empty(); });
  if (r == nullptr) return t;
  t.header = {"hop (" + r->stem() + ")", "kind", "mean ms", "p50 ms", "p99 ms"};
  t.numeric = {false, false, true, true, true};
  for (const auto& hop : r->hops) {
    t.rows.push_back({hop.label, hop.kind, format_fixed(hop.mean_ms, 3),
                      format_fixed(hop.p50_ms, 3), format_fixed(hop.p99_ms, 3)});
    t.row_warning.push_back(false);
  }
  return t;
}

// The newest grey-box run's callbacks: how long each node's callback for each trigger ran.
Table callbacks_table_for(const std::vector<const StoredRun*>& runs) {
  Table t;
  t.css_class = "callbacks";
  const StoredRun* r = newest_where(runs, [](const StoredRun& x) { return !x.callbacks.empty(); });
  if (r == nullptr) return t;
  t.header = {
      "node (" + r->stem() + ")", "callback of", "count", "mean ms", "p50 ms", "p99 ms", "max ms"};
  t.numeric = {false, false, true, true, true, true, true};
  for (const auto& cb : r->callbacks) {
    t.rows.push_back({cb.node, cb.source, std::to_string(cb.count), format_fixed(cb.mean_ms, 3),
                      format_fixed(cb.p50_ms, 3), format_fixed(cb.p99_ms, 3),
                      format_fixed(cb.max_ms, 3)});
    t.row_warning.push_back(false);
  }
  return t;
}

// The benchmark's configurations with enough runs for a trend, each with its change points.
std::vector<HistorySeries> trends_for(const std::string& id, const std::vector<StoredRun>& runs) {
  HistoryOptions options;
  options.benchmark_id = id;
  History h;
  try {
    h = history(runs, options);
  } catch (const ReportError&) {
    return {};  // no valid run with a p50: nothing to draw
  }
  std::vector<HistorySeries> out;
  for (auto& series : h.series) {
    if (series.points.size() >= detail::kTrendPoints) out.push_back(std::move(series));
  }
  return out;
}

// Each --find-peak run's search, step by step, as its terminal summary shows it.
Table peak_search_table_for(const std::vector<const StoredRun*>& runs) {
  Table t;
  t.css_class = "peak-search";
  t.header = {"run",       "step",   "rate Hz",    "offered Hz",
              "output Hz", "loss %", "latency ms", "verdict"};
  t.numeric = {false, true, true, true, true, true, true, false};
  for (const StoredRun* r : runs) {
    for (std::size_t i = 0; i < r->peak_steps.size(); ++i) {
      const auto& step = r->peak_steps[i];
      std::string verdict = step.passed ? "sustained" : "failed: " + step.reason;
      if (i + 1 == r->peak_steps.size() && !r->peak_stop_reason.empty())
        verdict += " (" + r->peak_stop_reason + ")";
      t.rows.push_back({i == 0 ? r->stem() : "", std::to_string(i + 1),
                        format_fixed(step.rate_hz, 1), format_fixed(step.offered_hz, 1),
                        format_fixed(step.output_hz, 1), format_fixed(step.loss_percent, 2),
                        format_fixed(step.latency_ms, 3), verdict});
      t.row_warning.push_back(false);
    }
  }
  return t;
}

void published_tables(const PublishedBenchmark& b, Table& summary, Table& flagged) {
  summary.css_class = "published";
  summary.header = {"hardware",
                    "type",
                    "category",
                    "rows",
                    "latency ms (median)",
                    "throughput fps (median)",
                    "power W (median)",
                    "rates stated",
                    "flagged rows"};
  summary.numeric = {false, false, false, true, true, true, true, false, true};
  // Per hardware and type: black- and grey-box rows are two measurements, never one median.
  using Key = std::pair<std::string, std::string>;
  std::vector<Key> order;
  std::map<Key, std::map<std::string, std::vector<double>>> values;
  std::map<Key, std::size_t> rows, flags;
  std::map<Key, std::set<std::string>> categories, rates;
  for (const auto& r : b.results) {
    const Key key{r.hardware, r.type};
    if (!rows.contains(key)) order.push_back(key);
    ++rows[key];
    categories[key].insert(r.category);
    if (const auto rate = r.stated_rate(); !rate.empty()) rates[key].insert(rate);
    if (!r.flags.empty()) {
      ++flags[key];
    } else {
      values[key][r.metric].push_back(r.value);
    }
  }
  for (const auto& key : order) {
    const std::string stated = joined(rates[key], ", ");
    summary.rows.push_back({key.first, key.second.empty() ? "-" : key.second,
                            joined(categories[key], ", "), std::to_string(rows[key]),
                            detail::format_value(median(values[key]["latency"])),
                            detail::format_value(median(values[key]["throughput"])),
                            detail::format_value(median(values[key]["power"])),
                            stated.empty() ? "-" : stated, std::to_string(flags[key])});
    summary.row_warning.push_back(false);
    summary.row_tags.push_back({{"system", key.first},
                                {"source", "published RobotPerf"},
                                {"mode", key.second.empty() ? "black" : key.second}});
  }
  flagged.css_class = "flagged";
  flagged.header = {"line", "hardware", "metric", "value", "why it breaks the measurement rules"};
  flagged.numeric = {true, false, false, true, false};
  for (const auto& r : b.results) {
    if (r.flags.empty()) continue;
    flagged.rows.push_back(
        {b.source.filename().string() + ":" + std::to_string(r.line), r.hardware, r.metric,
         (r.value_text.empty() ? "?" : r.value_text) + " " + r.metric_unit, joined(r.flags, "; ")});
    flagged.row_warning.push_back(true);
  }
}

// --- per-benchmark bars and the published standing -----------------------------------------

// Several values as one bar: their median, with its distribution-free 95 % interval where the
// values bound it (six or more), and each value as a point when there are several.
detail::Bar bar_of(const std::vector<double>& values, const char* one, const char* several) {
  detail::Bar bar;
  bar.value = median(values);
  bar.count = std::to_string(values.size()) + " " + (values.size() == 1 ? one : several);
  if (values.size() > 1) {
    bar.points = values;
    const auto ci = metrics::compute_stats(values).p50_ci;
    bar.lower = ci.lower;
    bar.upper = ci.upper;
  }
  return bar;
}

// A configuration's valid runs of one benchmark, in the order they ran: a --repeat series is one
// configuration, and so one bar.
std::vector<std::pair<std::string, std::vector<const StoredRun*>>> configurations_of(
    const std::vector<const StoredRun*>& runs) {
  std::vector<std::pair<std::string, std::vector<const StoredRun*>>> out;
  for (const StoredRun* r : runs) {
    if (!r->valid) continue;
    const std::string name = detail::local_series(*r);
    auto it = std::ranges::find(out, name, &decltype(out)::value_type::first);
    if (it == out.end()) it = out.emplace(out.end(), name, std::vector<const StoredRun*>{});
    it->second.push_back(r);
  }
  return out;
}

void sort_bars(detail::BarChart& chart) {
  std::erase_if(chart.bars, [](const detail::Bar& b) { return !std::isfinite(b.value); });
  std::ranges::stable_sort(chart.bars, {}, &detail::Bar::value);
}

// The latency bars of a benchmark: the local configurations' p50 (what a run's latency is like),
// and, where published rows exist, the maximum beside them, since RobotPerf reports the maximum:
// a p50 beside a published maximum would compare two figures.
std::vector<detail::BarChart> charts_for(const std::string& id,
                                         const std::vector<const StoredRun*>& runs,
                                         const ReportInput& in,
                                         const std::vector<Observation>& obs) {
  std::vector<detail::BarChart> out;
  const auto configurations = configurations_of(runs);
  detail::BarChart p50{id,
                       "p50",
                       "p50 latency from the scheduled send (ms); several runs: the median of "
                       "their p50s",
                       {},
                       {}};
  for (const auto& [name, of] : configurations) {
    std::vector<double> values;
    for (const StoredRun* r : of) values.push_back(r->latency.p50);
    detail::Bar bar = bar_of(values, "run", "runs");
    if (of.size() == 1) {  // one run: the interval of its own p50
      bar.lower = of.front()->latency.p50_lower;
      bar.upper = of.front()->latency.p50_upper;
    }
    bar.series = name;
    bar.tags = tags_of(*of.front());
    p50.bars.push_back(std::move(bar));
  }
  sort_bars(p50);
  if (!p50.bars.empty()) out.push_back(std::move(p50));

  std::vector<std::pair<std::string, std::vector<const PublishedResult*>>> published;
  for (const auto& b : in.published) {
    if (b.id != id) continue;
    for (const auto& row : b.results) {
      if (!row.flags.empty() || row.metric != "latency" || !std::isfinite(row.value)) continue;
      const std::string name = detail::published_series(row);
      auto it = std::ranges::find(published, name, &decltype(published)::value_type::first);
      if (it == published.end())
        it = published.emplace(published.end(), name, std::vector<const PublishedResult*>{});
      it->second.push_back(&row);
    }
  }
  if (published.empty()) return out;
  detail::BarChart max{id,
                       "max",
                       "maximum latency (ms), as RobotPerf reports it; several runs or rows: the "
                       "median of their maxima",
                       {},
                       {}};
  for (const auto& [name, of] : configurations) {
    std::vector<double> values;
    for (const StoredRun* r : of) values.push_back(r->latency.max);
    detail::Bar bar = bar_of(values, "run", "runs");
    bar.series = name;
    bar.tags = tags_of(*of.front());
    max.bars.push_back(std::move(bar));
  }
  for (const auto& [name, rows] : published) {
    std::vector<double> values;
    for (const PublishedResult* row : rows) values.push_back(row->value);
    detail::Bar bar = bar_of(values, "row", "rows");
    bar.points.clear();  // dozens of rows would hide the bar; their spread is the whisker
    bar.series = name;
    bar.local = false;
    bar.tags = tags_of(*rows.front());
    max.bars.push_back(std::move(bar));
  }
  std::vector<Observation> mine;
  std::ranges::copy_if(obs, std::back_inserter(mine),
                       [&](const Observation& o) { return o.benchmark_id == id; });
  if (!mine.empty()) max.notes = differences_on_axes(mine.front().category, "latency", "ms", mine);
  sort_bars(max);
  out.push_back(std::move(max));
  return out;
}

// Each local black-box configuration against the published rows measured alike, by the rule the
// summary's verdict uses (report/standing.hpp): black-box latency rows that pass the measurement
// rules and state the rate the configuration ran at; maxima on both sides, as RobotPerf reports
// latency.
Table versus_published_for(const std::string& id, const std::vector<const StoredRun*>& runs,
                           const ReportInput& in, std::vector<double>& ratios) {
  Table t;
  t.css_class = "versus-published";
  t.header = {"configuration",
              "max latency ms (median)",
              "published rows alike",
              "published median ms",
              "this / median",
              "best published",
              "best ms",
              "standing"};
  t.numeric = {false, true, true, true, true, false, true, false};
  for (const auto& [name, of] : configurations_of(runs)) {
    const StoredRun& first = *of.front();
    if (first.type == "grey" || first.throughput_kind == "peak") continue;
    std::vector<double> rates = {first.rate_hz};
    if (first.update_rate_hz) rates.push_back(*first.update_rate_hz);
    std::vector<double> mine;
    for (const StoredRun* r : of) mine.push_back(r->latency.max);
    // An older file without a maximum has no standing.
    const auto s = standing_among(median(mine), id, first.benchmark_name, rates, in.published);
    if (!s) continue;
    t.rows.push_back({name, detail::format_value(s->value_ms), std::to_string(s->rows),
                      detail::format_value(s->median_ms),
                      format_fixed(s->value_ms / s->median_ms, 2), s->best_platform,
                      detail::format_value(s->best_ms),
                      "lower than " + std::to_string(s->slower) + " of " +
                          std::to_string(s->platforms) + " published systems"});
    t.row_warning.push_back(false);
    t.row_tags.push_back(tags_of(first));
    ratios.push_back(s->value_ms / s->median_ms);
  }
  return t;
}

// --- comparison ----------------------------------------------------------------------------

struct Side {
  std::string label;
  std::vector<const StoredRun*> runs;
  std::vector<std::pair<const PublishedBenchmark*, const PublishedResult*>> rows;
  // The fields the selector chose (rmw=..., or hardware for a hardware name): a difference in
  // them is the one asked about; any other is named beside the comparison.
  std::set<std::string> selected_fields;
};

// What docs/design.md §3.9 requires two compared results to share, field by field, named as a
// selector names them; a published row states only its hardware, type and rate. Empty values
// are unknown.
using Configuration = std::vector<std::pair<std::string, std::string>>;

Configuration configuration_of(const StoredRun& r) {
  Configuration c = {{"hardware", r.hardware},
                     {"rmw", r.rmw},
                     {"processes", r.processes},
                     {"backend", r.backend.empty() ? "cpu" : r.backend},
                     {"mode", r.type},
                     {"arrivals", r.timeline},
                     {"monitor", r.monitor_wait},
                     {"network", r.network},
                     {"rate", rate_text(r)},
                     {"node settings", r.node_settings}};
  for (const auto& [key, value] : r.labels) c.emplace_back("label." + key, value);
  return c;
}

Configuration configuration_of(const PublishedResult& row) {
  return {{"hardware", row.hardware}, {"mode", row.type}, {"rate", row.stated_rate()}};
}

std::string configuration_value(const Configuration& c, const std::string& field) {
  const auto it = std::ranges::find(c, field, &Configuration::value_type::first);
  return it == c.end() ? "" : it->second;
}

// "rate 200 Hz vs 10 Hz" for each field both sides state and state differently, except `skip`.
std::vector<std::string> differences(const Configuration& a, const Configuration& b,
                                     const std::set<std::string>& skip) {
  std::vector<std::string> out;
  for (const auto& [field, value] : a) {
    const std::string other = configuration_value(b, field);
    if (skip.contains(field) || value.empty() || other.empty() || value == other) continue;
    out.push_back(field + " " + value + " vs " + other);
  }
  return out;
}

// A selector of fields, "rmw=fastdds,processes=per-node,rate=30": each field a run must have.
// Published rows have only a hardware, a type (mode) and the rate their note states; a selector
// naming another field selects no published row.
struct FieldSelector {
  std::map<std::string, std::string> fields;  // lower-case values

  static std::optional<FieldSelector> parse(const std::string& selector) {
    if (selector.find('=') == std::string::npos) return std::nullopt;
    FieldSelector f;
    std::stringstream parts(selector);
    std::string part;
    while (std::getline(parts, part, ',')) {
      const auto eq = part.find('=');
      std::string key = lower(part.substr(0, eq));
      // system= is hardware= under the name --system gives it; label.KEY= a run's label.
      if (key == "system") key = "hardware";
      if (eq == std::string::npos || !(kKeys.contains(key) || key.starts_with("label."))) {
        throw ReportError("'" + selector + "': '" + part +
                          "' is not a field=value (fields: hardware or system, rmw, processes, "
                          "backend, mode, arrivals, monitor, rate, label.KEY)");
      }
      f.fields[key] = lower(part.substr(eq + 1));
    }
    return f;
  }
  bool matches(const StoredRun& r) const {
    for (const auto& [key, want] : fields) {
      if (key.starts_with("label.")) {
        const auto label = r.labels.find(key.substr(6));
        if (label == r.labels.end() || lower(label->second) != want) return false;
        continue;
      }
      if (key == "rate") {
        // A control benchmark's run is named by its input rate (its series) and by its
        // controller loop's (its notes, as published rows state theirs): either picks it. Two
        // configurations that one rate picks are refused as a pool, as any others.
        if (!same_rate(r.rate_hz, want) &&
            !(r.update_rate_hz && same_rate(*r.update_rate_hz, want)))
          return false;
        continue;
      }
      const std::string have = key == "hardware"    ? r.hardware
                               : key == "rmw"       ? r.rmw
                               : key == "processes" ? r.processes
                               : key == "backend"   ? (r.backend.empty() ? "cpu" : r.backend)
                               : key == "mode"      ? r.type
                               : key == "monitor"   ? r.monitor_wait
                                                    : r.timeline;
      if (lower(have) != want) return false;
    }
    return true;
  }
  bool matches(const PublishedResult& row) const {
    for (const auto& [key, want] : fields) {
      if (key == "rate") {
        if (!row.note_rate_hz || row.note_rate_hz->first != row.note_rate_hz->second ||
            !same_rate(row.note_rate_hz->first, want))
          return false;
        continue;
      }
      if (key == "hardware" ? lower(row.hardware) != want
                            : key != "mode" || lower(row.type) != want) {
        return false;
      }
    }
    return true;
  }
  static bool same_rate(double hz, const std::string& want) {
    char* end = nullptr;
    const double wanted = std::strtod(want.c_str(), &end);
    return *end == '\0' && std::fabs(hz - wanted) <= 1e-6 * std::max(1.0, wanted);
  }

  static inline const std::set<std::string> kKeys = {"hardware", "rmw",      "processes", "backend",
                                                     "mode",     "arrivals", "monitor",   "rate"};
};

Side select(const std::string& selector, const ReportInput& in) {
  Side side;
  side.label = selector;
  const std::string want = lower(selector);
  auto by_file = [&](const StoredRun& r) {
    return r.path.string() == selector || r.path.filename().string() == selector ||
           r.stem().starts_with(selector);
  };
  auto run_named = [&](const StoredRun& r) {
    return by_file(r) || lower(r.hardware) == want || lower(detail::local_series(r)) == want;
  };
  auto row_named = [&](const PublishedResult& row) {
    return row.flags.empty() &&
           (lower(row.hardware) == want || lower(detail::published_series(row)) == want);
  };
  // What names a run or a published row is taken as that name: a hardware name may hold '='
  // ("ACME x=1"), which would otherwise read as fields.
  const bool a_name = std::ranges::any_of(in.runs, run_named) ||
                      std::ranges::any_of(in.published, [&](const PublishedBenchmark& b) {
                        return std::ranges::any_of(b.results, row_named);
                      });
  const std::optional<FieldSelector> by_fields =
      a_name ? std::nullopt : FieldSelector::parse(selector);
  if (by_fields) {
    for (const auto& [key, value] : by_fields->fields) side.selected_fields.insert(key);
  }
  for (const auto& r : in.runs) {
    if (by_fields ? by_fields->matches(r) : run_named(r)) {
      side.runs.push_back(&r);
      // A name chooses what it spells: "a1-fastdds" chooses the transport, so that comparing it
      // with "a1-intra" is not called unlike in the very field compared.
      if (!by_fields) {
        for (const auto& [field, value] : configuration_of(r)) {
          if (!value.empty() && want.find(lower(value)) != std::string::npos)
            side.selected_fields.insert(field);
        }
      }
    }
    if (!by_fields && lower(r.hardware) == want) side.selected_fields.insert("hardware");
  }
  for (const auto& b : in.published) {
    for (const auto& row : b.results) {
      if (!row.flags.empty()) continue;
      if (by_fields ? by_fields->matches(row) : row_named(row)) side.rows.emplace_back(&b, &row);
      if (!by_fields && lower(row.hardware) == want) side.selected_fields.insert("hardware");
    }
  }
  if (side.runs.empty() && side.rows.empty()) {
    std::set<std::string> known;
    for (const auto& r : in.runs) known.insert(detail::local_series(r));
    for (const auto& b : in.published)
      for (const auto& row : b.results) known.insert(row.hardware);
    std::string list;
    std::size_t shown = 0;
    for (const auto& k : known) {
      if (shown++ == 8) {
        list += ", ...";
        break;
      }
      list += (list.empty() ? "" : ", ") + k;
    }
    throw ReportError("'" + selector + "' matches no results file and no hardware (known: " + list +
                      ")");
  }
  return side;
}

struct CompareMetric {
  const char* name;
  const char* unit;
  bool smaller_is_better;
};
constexpr CompareMetric kCompareMetrics[] = {{"latency max", "ms", true},
                                             {"latency mean", "ms", true},
                                             {"latency p50", "ms", true},
                                             {"throughput", "fps", false},
                                             {"power", "W", true}};

std::vector<double> side_values(const Side& s, const std::string& id, const std::string& metric,
                                std::vector<const StoredRun*>* runs_used) {
  std::vector<double> v;
  for (const StoredRun* r : s.runs) {
    if (r->benchmark_id != id || !r->valid) continue;
    double x = kNoValue;
    if (metric == "latency max") x = r->latency.max;
    if (metric == "latency mean") x = r->latency.mean;
    if (metric == "latency p50") x = r->latency.p50;
    if (metric == "throughput") x = r->throughput_hz;
    if (metric == "power" && r->power_w) x = *r->power_w;
    if (std::isfinite(x)) {
      v.push_back(x);
      if (runs_used) runs_used->push_back(r);
    }
  }
  for (const auto& [b, row] : s.rows) {
    if (b->id != id) continue;
    double x = kNoValue;
    if (metric == "latency max" && row->metric == "latency") x = row->value;
    if (metric == "latency mean" && row->metric == "latency" && row->note_mean) x = *row->note_mean;
    if (metric == "throughput" && row->metric == "throughput") x = row->value;
    if (metric == "power" && row->metric == "power") x = row->value;
    if (std::isfinite(x)) v.push_back(x);
  }
  return v;
}

detail::Comparison compare(const std::string& a_sel, const std::string& b_sel,
                           const ReportInput& in) {
  const Side a = select(a_sel, in);
  const Side b = select(b_sel, in);
  detail::Comparison c;
  c.a = a_sel;
  c.b = b_sel;
  c.table.css_class = "comparison";
  c.table.header = {"benchmark",  "metric", "A (median)", "n A",
                    "B (median)", "n B",    "B / A",      "judgement"};
  c.table.numeric = {false, false, true, true, true, true, true, false};
  std::set<std::string> ids;
  for (const auto* r : a.runs) ids.insert(r->benchmark_id);
  for (const auto& [bench, row] : a.rows) ids.insert(bench->id);
  // A side is one configuration per benchmark: a median over intra and fastdds runs, 30 and
  // 60 Hz, two machines, or local runs and published rows describes none of them. A published
  // row's configuration is its hardware, type and stated rate.
  std::map<std::string, Configuration> configuration_a, configuration_b;
  for (const auto& [side, selector, configuration] :
       {std::tuple{&a, a_sel, &configuration_a}, std::tuple{&b, b_sel, &configuration_b}}) {
    for (const auto& id : ids) {
      std::set<std::string> configurations;
      for (const StoredRun* r : side->runs) {
        if (r->benchmark_id != id || !r->valid) continue;
        // Runs whose nodes computed with other parameters or kernels did other work.
        configurations.insert(detail::local_series(*r) +
                              (r->node_settings.empty() ? "" : " · " + r->node_settings));
        (*configuration)[id] = configuration_of(*r);
      }
      for (const auto& [bench, row] : side->rows) {
        if (bench->id != id) continue;
        const std::string rate = row->stated_rate();
        configurations.insert(row->hardware + " (RobotPerf) · " + row->type +
                              (rate.empty() ? "" : " · " + rate));
        (*configuration)[id] = configuration_of(*row);
      }
      if (configurations.size() > 1) {
        // A few of them name the choice; a lab's folder can hold thousands.
        constexpr std::size_t kNamed = 4;
        std::vector<std::string> named(
            configurations.begin(),
            std::next(configurations.begin(),
                      static_cast<std::ptrdiff_t>(std::min(kNamed, configurations.size()))));
        std::string list = joined(named, "; ");
        if (configurations.size() > kNamed)
          list += "; and " + std::to_string(configurations.size() - kNamed) + " more";
        throw ReportError("'" + selector + "' selects " + std::to_string(configurations.size()) +
                          " configurations of " + id + " (" + list +
                          "): name one series, or narrow the side with fields, e.g. "
                          "'hardware=...,rmw=fastdds,processes=single,mode=black,rate=30'");
      }
    }
  }
  std::set<std::string> selected = a.selected_fields;
  selected.insert(b.selected_fields.begin(), b.selected_fields.end());
  for (const auto& id : ids) {
    const Configuration& ca = configuration_a[id];
    const Configuration& cb = configuration_b[id];
    if (const auto unlike = differences(ca, cb, selected); !unlike.empty()) {
      c.notes.push_back("Not alike: " + id + ": besides what was selected, A and B differ in " +
                        joined(unlike, "; ") +
                        ", so a difference in the table is not the selected one's alone");
    }
    // An offered throughput is the rate the input was fed at: at two rates it is no result.
    const std::string rate_a = configuration_value(ca, "rate");
    const std::string rate_b = configuration_value(cb, "rate");
    const bool unlike_rates = !rate_a.empty() && !rate_b.empty() && rate_a != rate_b;
    for (const auto& m : kCompareMetrics) {
      std::vector<const StoredRun*> runs_a, runs_b;
      const auto va = side_values(a, id, m.name, &runs_a);
      const auto vb = side_values(b, id, m.name, &runs_b);
      if (va.empty() || vb.empty()) continue;
      const double ma = median(va), mb = median(vb);
      const double ratio = mb / ma;
      // With enough runs a side's median has a distribution-free 95 % interval (as --repeat
      // prints it): disjoint intervals are a difference beyond the run-to-run noise.
      const metrics::PercentileInterval ia = metrics::compute_stats(va).p50_ci;
      const metrics::PercentileInterval ib = metrics::compute_stats(vb).p50_ci;
      auto closed = [](const metrics::PercentileInterval& i) {
        return !std::isnan(i.lower) && !std::isnan(i.upper);
      };
      auto with_interval = [&](double m, const metrics::PercentileInterval& i) {
        return detail::format_value(m) + (closed(i) ? " [" + detail::format_value(i.lower) + ", " +
                                                          detail::format_value(i.upper) + "]"
                                                    : "");
      };
      std::string judgement;
      std::optional<double> p;
      std::string basis;
      if (std::string(m.name) == "throughput" && unlike_rates) {
        judgement = "not judged: the rates differ (A " + rate_a + ", B " + rate_b +
                    "); an offered throughput is the rate the input was fed at, not a result";
      } else if (closed(ia) && closed(ib)) {
        const bool better = m.smaller_is_better ? mb < ma : mb > ma;
        judgement = ia.upper < ib.lower || ib.upper < ia.lower
                        ? std::string("significant: B ") + (better ? "better" : "worse") +
                              " (the medians' 95 % intervals do not overlap)"
                        : "within run-to-run noise (the medians' 95 % intervals overlap)";
      } else if (va.size() >= 2 && vb.size() >= 2) {
        p = welch_test(va, vb).p_value;
        basis = "run-to-run spread";
      } else if (std::string(m.name) == "latency mean" && runs_a.size() == 1 &&
                 runs_b.size() == 1 && va.size() == 1 && vb.size() == 1 &&
                 runs_a[0]->latency.count >= 2 && runs_b[0]->latency.count >= 2) {
        const auto& la = runs_a[0]->latency;
        const auto& lb = runs_b[0]->latency;
        p = welch_test(la.mean, la.stddev, la.count, lb.mean, lb.stddev, lb.count).p_value;
        basis = "within-run spread only; repeat the runs to judge run-to-run";
      }
      if (p) {
        const bool better = m.smaller_is_better ? mb < ma : mb > ma;
        char buf[96];
        std::snprintf(buf, sizeof buf, "p = %.2g", *p);
        judgement = (*p < 0.05 ? std::string("significant: B ") + (better ? "better" : "worse")
                               : std::string("not significant")) +
                    " (" + buf + ", " + basis + ")";
      } else if (judgement.empty()) {
        judgement = "not judged: needs 2 or more runs per side";
      }
      c.table.rows.push_back({id, std::string(m.name) + " (" + m.unit + ")", with_interval(ma, ia),
                              std::to_string(va.size()), with_interval(mb, ib),
                              std::to_string(vb.size()), format_fixed(ratio, 3), judgement});
      c.table.row_warning.push_back(false);
    }
  }
  c.notes.push_back("A = " + a_sel + ": " + std::to_string(a.runs.size()) + " local runs, " +
                    std::to_string(a.rows.size()) + " published rows");
  c.notes.push_back("B = " + b_sel + ": " + std::to_string(b.runs.size()) + " local runs, " +
                    std::to_string(b.rows.size()) + " published rows");
  if (c.table.rows.empty())
    c.notes.push_back("The two sides have no benchmark and metric in common.");
  return c;
}

// Without --compare: the two local configurations that share the most benchmarks, and among those
// the pair that differs in the fewest settings (the difference is then the one to read), or why
// there is none. Two configurations with nothing in common are never compared.
void automatic_comparison(detail::Model& model, const ReportInput& in) {
  std::vector<std::string> names;
  std::map<std::string, std::set<std::string>> ids;
  std::map<std::string, Configuration> configuration;
  for (const auto& r : in.runs) {
    if (!r.valid) continue;
    const std::string name = detail::local_series(r);
    if (!ids.contains(name)) names.push_back(name);
    ids[name].insert(r.benchmark_id);
    configuration[name] = configuration_of(r);
  }
  if (names.size() < 2) return;
  struct Candidate {
    std::size_t shared, differences, a, b;
  };
  std::vector<Candidate> candidates;
  for (std::size_t a = 0; a < names.size(); ++a) {
    for (std::size_t b = a + 1; b < names.size(); ++b) {
      std::size_t shared = 0;
      for (const auto& id : ids[names[a]]) shared += ids[names[b]].contains(id);
      if (shared == 0) continue;
      candidates.push_back(
          {shared, differences(configuration[names[a]], configuration[names[b]], {}).size(), a, b});
    }
  }
  std::ranges::stable_sort(candidates, [](const Candidate& x, const Candidate& y) {
    return std::tie(y.shared, x.differences) < std::tie(x.shared, y.differences);
  });
  for (const auto& c : candidates) {
    try {
      detail::Comparison comparison = compare(names[c.a], names[c.b], in);
      if (comparison.table.rows.empty()) continue;
      model.comparison = std::move(comparison);
      return;
    } catch (const ReportError&) {
      // A series whose runs' node settings differ is no one side: try the next pair.
    }
  }
  model.no_comparison =
      "No automatic comparison: no two local configurations ran a benchmark in common "
      "(--compare A --compare B compares any two sides).";
}

// --- the executive summary -----------------------------------------------------------------

// One colour per series across the page: local configurations in the order they first ran, then
// the published series of the radars (a polygon needs a colour to be told apart). The palette's
// eight go to the first eight; the others are drawn in outline, named where they are drawn, so no
// colour means two series. A published bar is hatched and named beside it: it takes a colour only
// where a radar gave its series one.
void assign_colours(detail::Model& model, const ReportInput& in) {
  std::map<std::string, std::size_t> colour;
  auto give = [&](const std::string& name, bool local) {
    const std::size_t next =
        model.key.size() < std::size(detail::kPalette) ? model.key.size() : detail::kNoColour;
    const auto [it, added] = colour.try_emplace(name, next);
    if (added) model.key.push_back({name, next, local});
    return it->second;
  };
  for (const auto& r : in.runs) {
    if (r.valid) give(detail::local_series(r), true);
  }
  for (auto& [category, radars] : model.radars) {
    for (auto& radar : radars) {
      for (std::size_t i = 0; i < radar.series.size(); ++i)
        radar.colours.push_back(give(radar.series[i], radar.series_local[i]));
    }
  }
  for (auto& [category, sections] : model.benchmarks) {
    for (auto& section : sections) {
      for (auto& chart : section.charts) {
        for (auto& bar : chart.bars) {
          const auto it = colour.find(bar.series);
          bar.colour = bar.local            ? give(bar.series, true)
                       : it == colour.end() ? detail::kNoColour
                                            : it->second;
        }
      }
      for (auto& curve : section.distribution) {
        if (curve.valid) curve.colour = give(curve.series, true);
      }
    }
  }
}

// The filters offer what the page's rows and bars are tagged with, where there is a choice.
void collect_filters(detail::Model& model) {
  std::map<std::string, std::set<std::string>> values;
  auto add = [&](const std::map<std::string, std::string>& tags) {
    for (const auto& [group, value] : tags) values[group].insert(value);
  };
  for (const auto& [category, sections] : model.benchmarks) {
    for (const auto& section : sections) {
      for (const auto& chart : section.charts) {
        for (const auto& bar : chart.bars) add(bar.tags);
      }
      for (const auto& tags : section.runs.row_tags) add(tags);
      for (const auto& tags : section.published.row_tags) add(tags);
    }
  }
  std::vector<std::string> groups = {"system", "transport", "source", "mode"};
  for (const auto& [group, v] : values) {
    if (group.starts_with("label-")) groups.push_back(group);
  }
  for (const auto& group : groups) {
    const auto& v = values[group];
    if (v.size() >= 2)
      model.filters.emplace_back(group, std::vector<std::string>(v.begin(), v.end()));
  }
}

// "1 run", "3 runs".
std::string counted(std::size_t n, const std::string& what) {
  return std::to_string(n) + " " + what + (n == 1 ? "" : "s");
}

std::string times(double ratio) {
  return format_fixed(ratio, ratio < 10 ? 2 : 1) + "×";
}

void summarise(detail::Model& model, const ReportInput& in, std::size_t published_rows,
               std::size_t flagged_rows) {
  std::vector<std::string> ids, systems, published_systems;
  std::set<std::string> configurations;
  for (const auto& r : in.runs) {
    if (std::ranges::find(ids, r.benchmark_id) == ids.end()) ids.push_back(r.benchmark_id);
    if (std::ranges::find(systems, r.hardware) == systems.end()) systems.push_back(r.hardware);
    configurations.insert(detail::local_series(r));
  }
  std::set<std::string> published_ids, published_hardware;
  for (const auto& b : in.published) {
    published_ids.insert(b.id);
    for (const auto& row : b.results) published_hardware.insert(row.hardware);
  }
  const auto valid = std::ranges::count_if(in.runs, [](const auto& r) { return r.valid; });
  if (!in.runs.empty()) {
    model.overview.push_back(
        "Ran " + counted(in.runs.size(), "run") + " (" + std::to_string(valid) + " valid) of " +
        counted(ids.size(), "benchmark") + " (" + joined(ids, ", ") + ") in " +
        counted(configurations.size(), "configuration") + " on " + joined(systems, ", ") + ".");
  } else {
    model.overview.push_back("No local runs: the published rows alone.");
  }
  if (!in.published.empty()) {
    model.overview.push_back("Beside them: " + counted(published_rows, "published RobotPerf row") +
                             " of " + counted(published_ids.size(), "benchmark") + " from " +
                             counted(published_hardware.size(), "system") + " (" +
                             std::to_string(flagged_rows) +
                             " break the measurement rules and are left out of every figure).");
  }

  model.at_a_glance.css_class = "at-a-glance";
  model.at_a_glance.header = {"benchmark",      "valid runs",
                              "configurations", "fastest (p50 latency)",
                              "p50 ms",         "vs published (max latency)"};
  model.at_a_glance.numeric = {false, true, true, false, true, false};
  std::map<std::string, std::vector<std::string>> wins;  // configuration -> benchmarks
  std::vector<std::string> wins_order;
  struct Difference {
    double ratio = 0;
    std::string text;
  } largest;
  std::vector<std::string> standing;
  std::size_t below_median = 0, with_standing = 0;
  for (const auto& category : model.categories) {  // in the page's order
    const auto& sections = model.benchmarks.at(category);
    for (const auto& section : sections) {
      std::size_t runs = 0, valid_runs = 0;
      for (const auto& r : in.runs) {
        if (r.benchmark_id != section.id) continue;
        ++runs;
        valid_runs += r.valid;
      }
      if (runs == 0) continue;
      const auto p50 =
          std::ranges::find(section.charts, std::string("p50"), &detail::BarChart::figure);
      std::string fastest = "-", fastest_value = "-", versus = "-";
      std::size_t configurations_here = 0;
      if (p50 != section.charts.end()) {
        const auto& bars = p50->bars;
        configurations_here = bars.size();
        fastest = bars.front().series;
        fastest_value = detail::format_value(bars.front().value);
        if (!wins.contains(fastest)) wins_order.push_back(fastest);
        wins[fastest].push_back(section.id);
        for (std::size_t i = 0; i < bars.size(); ++i) {
          for (std::size_t j = i + 1; j < bars.size(); ++j) {
            const auto& a = bars[i];  // the faster: bars are sorted
            const auto& b = bars[j];
            if (!std::isfinite(a.upper) || !std::isfinite(b.lower) || a.upper >= b.lower ||
                !(a.value > 0) || b.value / a.value <= largest.ratio)
              continue;
            largest.ratio = b.value / a.value;
            const bool within_run = a.points.empty() || b.points.empty();
            largest.text = "Largest significant difference: " + section.id + ": " + a.series +
                           " has " + times(largest.ratio) + " lower p50 latency than " + b.series +
                           " (" + detail::format_value(a.value) + " vs " +
                           detail::format_value(b.value) + " ms; their 95 % intervals do not " +
                           "overlap" +
                           (within_run ? "; from the spread within single runs: --repeat the runs "
                                         "to judge run-to-run)"
                                       : ")") +
                           ".";
          }
        }
      }
      const auto& vs = section.versus_published;
      if (!vs.rows.empty()) {
        // The configuration that stands best against the published rows measured alike.
        const auto& ratios = section.versus_ratios;
        const auto best =
            static_cast<std::size_t>(std::ranges::min_element(ratios) - ratios.begin());
        const double ratio = ratios[best];
        versus = times(ratio) + " the published median (" + vs.rows[best][2] + " rows alike)";
        ++with_standing;
        below_median += ratio < 1;
        standing.push_back(section.id + " " + times(ratio));
      }
      model.at_a_glance.rows.push_back(
          {section.id, std::to_string(valid_runs) + " of " + std::to_string(runs),
           std::to_string(configurations_here), fastest, fastest_value, versus});
      model.at_a_glance.row_warning.push_back(valid_runs < runs);
    }
  }
  if (!wins_order.empty()) {
    std::ranges::stable_sort(
        wins_order, [&](const auto& a, const auto& b) { return wins[a].size() > wins[b].size(); });
    std::vector<std::string> parts;
    for (std::size_t i = 0; i < wins_order.size() && i < 3; ++i)
      parts.push_back(wins_order[i] + " in " + joined(wins[wins_order[i]], ", "));
    if (wins_order.size() > 3) parts.push_back("others in the table below");
    model.findings.push_back("Fastest configuration (p50 latency): " + joined(parts, "; ") + ".");
  }
  if (!largest.text.empty()) {
    model.findings.push_back(largest.text);
  } else if (configurations.size() >= 2) {
    model.findings.push_back(
        "No difference between configurations of a benchmark is significant: their p50s' 95 % "
        "intervals overlap or are unknown.");
  }
  if (with_standing > 0) {
    model.findings.push_back(
        "Against the published RobotPerf rows measured alike (black-box, the same rate, maximum "
        "latency): below the published median in " +
        std::to_string(below_median) + " of " + std::to_string(with_standing) + " benchmarks (" +
        joined(standing, ", ") + " the median).");
  } else if (!in.published.empty() && !in.runs.empty()) {
    model.findings.push_back(
        "No local configuration has published rows measured alike (black-box, at the same rate): "
        "the published rows are shown beside the runs, not compared with them.");
  }
  if (!model.invalid_runs.empty()) {
    model.findings.push_back(std::to_string(model.invalid_runs.size()) + " INVALID run" +
                             (model.invalid_runs.size() == 1 ? " is" : "s are") +
                             " left out of every figure (listed under Validity).");
  } else if (!in.runs.empty()) {
    model.findings.push_back("All " + std::to_string(in.runs.size()) + " runs are valid.");
  }
}

// --- machines ------------------------------------------------------------------------------

std::string yes_no(const nlohmann::json& j) {
  return j.is_boolean() ? (j.get<bool>() ? "yes" : "no") : "-";
}

std::string text_or_dash(const nlohmann::json& j) {
  if (j.is_string()) return j.get<std::string>();
  if (j.is_number()) return j.dump();
  return "-";
}

Table machines_table(const std::vector<StoredRun>& runs) {
  Table t;
  t.css_class = "machines";
  t.header = {"hardware", "host",           "CPU",    "cores / threads", "frequency MHz",
              "governor", "memory GiB",     "kernel", "PREEMPT_RT",      "OS",
              "GPUs",     "container / VM", "runs"};
  t.numeric = std::vector<bool>(t.header.size(), false);
  std::vector<std::string> keys;
  std::map<std::string, std::vector<const StoredRun*>> by_machine;
  for (const auto& r : runs) {
    nlohmann::json m = r.json.value("machine", nlohmann::json::object());
    // The current frequency changes from run to run; the machine does not.
    if (!m.is_object()) m = nlohmann::json::object();
    if (m.contains("cpu") && m["cpu"].is_object() && m["cpu"].contains("frequency") &&
        m["cpu"]["frequency"].is_object()) {
      m["cpu"]["frequency"].erase("per_cpu");
      m["cpu"]["frequency"].erase("current_min_khz");
      m["cpu"]["frequency"].erase("current_max_khz");
    }
    const std::string key = m.dump();
    if (!by_machine.contains(key)) keys.push_back(key);
    by_machine[key].push_back(&r);
  }
  for (const auto& key : keys) {
    const auto& runs_of = by_machine[key];
    const nlohmann::json m = nlohmann::json::parse(key);
    auto object = [](const nlohmann::json& parent, const char* name) {
      const auto it = parent.find(name);
      return it != parent.end() && it->is_object() ? *it : nlohmann::json::object();
    };
    const nlohmann::json cpu = object(m, "cpu");
    const nlohmann::json freq = object(cpu, "frequency");
    auto mhz = [](const nlohmann::json& khz) {
      return khz.is_number() ? std::to_string(khz.get<std::uint64_t>() / 1000) : std::string("?");
    };
    std::string frequency =
        freq.contains("min_khz") && freq["min_khz"].is_number()
            ? mhz(freq["min_khz"]) + "–" + mhz(freq.value("max_khz", nlohmann::json()))
            : "-";
    std::string governors;
    // The machine is read here, after loading: each value is checked for its type, so that a
    // file from another writer shows "-" where it differs instead of stopping the report.
    for (const auto& g : freq.value("governors", nlohmann::json::array())) {
      if (g.is_string()) governors += (governors.empty() ? "" : ", ") + g.get<std::string>();
    }
    std::string gpus;
    for (const auto& g : m.value("gpus", nlohmann::json::array())) {
      std::string name = text_or_dash(g.is_object() ? g.value("model", nlohmann::json()) : g);
      if (name == "-" && g.is_object())
        name = text_or_dash(g.value("vendor_name", nlohmann::json())) + " " +
               text_or_dash(g.value("device_id", nlohmann::json()));
      gpus += (gpus.empty() ? "" : ", ") + name;
    }
    const nlohmann::json container = object(m, "container");
    std::string isolation =
        yes_no(container.value("detected", nlohmann::json())) == "yes"
            ? "container (" + text_or_dash(container.value("runtime", nlohmann::json())) + ")"
            : "no container";
    isolation += m.value("virtual_machine", nlohmann::json()).is_boolean() &&
                         m["virtual_machine"].get<bool>()
                     ? ", virtual machine"
                     : "";
    const auto mem = m.value("memory_total_bytes", nlohmann::json());
    std::string runs_list;
    for (const auto* r : runs_of) runs_list += (runs_list.empty() ? "" : ", ") + r->stem();
    const nlohmann::json kernel = object(m, "kernel");
    t.rows.push_back(
        {runs_of.front()->hardware, text_or_dash(m.value("hostname", nlohmann::json())),
         text_or_dash(cpu.value("model", nlohmann::json())),
         text_or_dash(cpu.value("physical_cores", nlohmann::json())) + " / " +
             text_or_dash(cpu.value("logical_cpus", nlohmann::json())),
         frequency, governors.empty() ? "-" : governors,
         mem.is_number() ? format_fixed(mem.get<double>() / (1024.0 * 1024 * 1024), 1) : "-",
         text_or_dash(kernel.value("release", nlohmann::json())),
         yes_no(kernel.value("preempt_rt", nlohmann::json())),
         text_or_dash(m.value("os", nlohmann::json())), gpus.empty() ? "none" : gpus, isolation,
         runs_list});
    t.row_warning.push_back(false);
  }
  return t;
}

}  // namespace

namespace detail {

// Okabe & Ito (2008), ordered so that the first series get the colours farthest from white.
const char* const kPalette[8] = {"#0072b2", "#e69f00", "#009e73", "#cc79a7",
                                 "#56b4e9", "#d55e00", "#000000", "#f0e442"};

const char* colour_of(std::size_t colour) {
  return colour < std::size(kPalette) ? kPalette[colour] : "#555555";
}

std::string configuration_series(const StoredRun& run) {
  // What makes two runs comparable (docs/design.md §3.9), the rate aside: the machine, the
  // transport, the process layout, the backend, black- or grey-box, the arrivals and how the
  // Monitor waited (a spinning one takes no wake-up out of each latency), the network path (a VPN
  // tunnel, a router). Defaults are left out of the label.
  std::string label = run.hardware + " · " + run.rmw;
  if (run.processes == "per-node") label += " · per-node";
  if (!run.backend.empty()) label += " · " + run.backend;
  if (run.type == "grey") label += " · grey";
  if (run.timeline != "fixed") label += " · " + run.timeline;
  if (run.monitor_wait == "spin") label += " · monitor spinning";
  if (run.network != "plain") label += " · " + run.network;
  // The user's labels (run --label) name series of their own; the automatic ones (robotperf's
  // version) are in the results but would split every series at each robotperf build.
  for (const auto& [key, value] : run.labels) {
    if (!key.starts_with("robotperf.")) label += " · " + key + "=" + value;
  }
  return label;
}

std::string local_series(const StoredRun& run) {
  // A peak search ends at whatever rate it found: the configuration's peak, not a rate's run.
  if (run.throughput_kind == "peak") return configuration_series(run) + " · peak";
  if (!std::isfinite(run.rate_hz)) return configuration_series(run);
  char rate[32];
  std::snprintf(rate, sizeof rate, "%.4g", run.rate_hz);  // 30, 29.97, 1000
  return configuration_series(run) + " · " + rate + " Hz";
}

std::string published_series(const PublishedResult& row) {
  // Black- and grey-box rows are two measurements, as local runs' series keep them apart.
  return row.hardware + (row.type == "grey" ? " · grey" : "") + " (RobotPerf)";
}

std::string format_value(double value) {
  if (!std::isfinite(value)) return "-";
  char buf[64];
  const double a = std::fabs(value);
  std::snprintf(buf, sizeof buf,
                a >= 1000  ? "%.0f"
                : a >= 100 ? "%.1f"
                : a >= 1   ? "%.2f"
                           : "%.3g",
                value);
  return buf;
}

std::string html_escape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

bool is_machine_warning(const std::string& warning) {
  for (const char* rule :
       {"build", "governor", "frequency", "turbo", "smt", "virtual_machine", "container"}) {
    if (warning.starts_with(std::string(rule) + ": ")) return true;
  }
  return false;
}

std::string warning_summary(const Model& model) {
  std::size_t machines = 0, machine_items = 0, run_items = 0;
  for (const auto& g : model.warning_groups) {
    if (g.heading.starts_with("machine ")) {
      ++machines;
      machine_items += g.items.size();
    } else {
      run_items += g.items.size();
    }
  }
  std::vector<std::string> parts;
  if (!model.invalid_runs.empty())
    parts.push_back(counted(model.invalid_runs.size(), "INVALID run"));
  if (machine_items > 0) {
    parts.push_back(counted(machine_items, "machine warning") + " (" +
                    counted(machines, "machine") + ")");
  }
  if (run_items > 0) parts.push_back(counted(run_items, "run warning"));
  if (!model.warnings.empty()) parts.push_back(counted(model.warnings.size(), "other warning"));
  return joined(parts, " · ");
}

Comparison build_comparison(const ReportInput& in, const std::string& a, const std::string& b) {
  return compare(a, b, in);
}

Selection select_runs(const std::string& selector, const ReportInput& in) {
  Side side = select(selector, in);
  return {std::move(side.runs), std::move(side.selected_fields)};
}

std::vector<std::string> unlike(const StoredRun& a, const StoredRun& b,
                                const std::set<std::string>& chosen) {
  return differences(configuration_of(a), configuration_of(b), chosen);
}

Model build_model(const ReportInput& in, const ReportOptions& options) {
  Model model;
  model.title = options.title;
  for (const auto& s : in.skipped) model.warnings.push_back("skipped " + s);

  std::set<std::string> categories;
  std::map<std::string, std::set<std::string>> ids_by_category;
  std::map<std::string, std::string> names;
  // Machine warnings by machine, each said once with the number of runs that recorded it.
  std::map<std::string, std::map<std::string, std::size_t>> machine_warnings;
  std::vector<WarningGroup> run_groups;
  for (const auto& r : in.runs) {
    categories.insert(r.category);
    ids_by_category[r.category].insert(r.benchmark_id);
    names[r.benchmark_id] = r.benchmark_name;
    if (!r.valid) {
      model.invalid_runs.push_back("run " + r.stem() +
                                   " is INVALID: " + joined(r.invalid_reasons, "; ") +
                                   " (shown in its table, left out of the plots)");
    }
    WarningGroup own{"run " + r.stem(), {}};
    for (const auto& w : r.warnings) {
      if (is_machine_warning(w)) {
        ++machine_warnings[r.hardware.empty() ? "unknown machine" : r.hardware][w];
      } else {
        own.items.push_back(w);
      }
    }
    if (!own.items.empty()) run_groups.push_back(std::move(own));
  }
  for (const auto& [machine, counted] : machine_warnings) {
    WarningGroup group{"machine " + machine, {}};
    for (const auto& [w, runs] : counted) {
      group.items.push_back(w + " (" + std::to_string(runs) + (runs == 1 ? " run)" : " runs)"));
    }
    model.warning_groups.push_back(std::move(group));
  }
  for (auto& group : run_groups) model.warning_groups.push_back(std::move(group));
  std::size_t published_rows = 0, flagged_rows = 0;
  for (const auto& b : in.published) {
    categories.insert(b.category);
    ids_by_category[b.category].insert(b.id);
    if (!names.contains(b.id)) names[b.id] = b.name;
    published_rows += b.results.size();
    flagged_rows += b.flagged();
    if (b.flagged() > 0) {
      model.warnings.push_back(b.source.string() + ": " + std::to_string(b.flagged()) + " of " +
                               std::to_string(b.results.size()) +
                               " published rows break the measurement rules (listed under " + b.id +
                               "; left out of the plots and comparisons)");
    }
  }
  // What ran here first: the categories with the most local runs, and in each the benchmarks with
  // local runs, before those with published rows alone.
  std::set<std::string> ran;
  std::map<std::string, std::size_t> runs_in;
  for (const auto& r : in.runs) {
    ran.insert(r.benchmark_id);
    ++runs_in[r.category];
  }
  model.categories.assign(categories.begin(), categories.end());
  std::ranges::stable_sort(model.categories, std::greater<>{},
                           [&](const std::string& c) { return runs_in[c]; });

  const auto obs = observations(in);
  for (const auto& category : model.categories) {
    model.radars[category] =
        options.radar ? radars_for(category, obs, options) : std::vector<Radar>{};
    std::vector<std::string> ids(ids_by_category[category].begin(),
                                 ids_by_category[category].end());
    std::ranges::stable_partition(ids, [&](const std::string& id) { return ran.contains(id); });
    for (const auto& id : ids) {
      BenchmarkSection section;
      section.id = id;
      section.name = names[id];
      section.category = category;
      std::vector<const StoredRun*> runs;
      for (const auto& r : in.runs) {
        if (r.benchmark_id == id) runs.push_back(&r);
      }
      section.runs = runs_table_for(runs);
      section.charts = charts_for(id, runs, in, obs);
      section.versus_published = versus_published_for(id, runs, in, section.versus_ratios);
      section.also_measured = also_measured_table_for(runs);
      section.outputs = outputs_table_for(runs);
      section.hops = hops_table_for(runs);
      section.callbacks = callbacks_table_for(runs);
      section.peak_search = peak_search_table_for(runs);
      if (const StoredRun* grey =
              newest_where(runs, [](const StoredRun& x) { return !x.hops.empty(); })) {
        section.hops_run = grey->stem();
        section.hop_bars = grey->hops;
      }
      std::vector<const StoredRun*> recent(
          runs.end() -
              static_cast<std::ptrdiff_t>(std::min(runs.size(), options.max_distribution_runs)),
          runs.end());
      section.distribution = distributions(recent, model.warnings);
      section.trends = trends_for(id, in.runs);
      for (const auto& b : in.published) {
        if (b.id != id) continue;
        Table summary, flagged;
        published_tables(b, summary, flagged);
        // Several files of one benchmark: append.
        if (section.published.header.empty()) {
          section.published = std::move(summary);
          section.flagged = std::move(flagged);
        } else {
          for (std::size_t i = 0; i < summary.rows.size(); ++i) {
            section.published.rows.push_back(summary.rows[i]);
            section.published.row_warning.push_back(false);
            section.published.row_tags.push_back(summary.row_tags[i]);
          }
          for (std::size_t i = 0; i < flagged.rows.size(); ++i) {
            section.flagged.rows.push_back(flagged.rows[i]);
            section.flagged.row_warning.push_back(true);
          }
        }
        section.published_rows += b.results.size();
      }
      model.benchmarks[category].push_back(std::move(section));
    }
  }

  if (options.compare) {
    model.comparison = compare(options.compare->first, options.compare->second, in);
  } else {
    automatic_comparison(model, in);
  }
  model.machines = machines_table(in.runs);
  assign_colours(model, in);
  collect_filters(model);
  summarise(model, in, published_rows, flagged_rows);

  model.summary = std::string("robotperf ") + build_info::kVersion + ".";
  return model;
}

// Characters as a terminal shows them: UTF-8 continuation bytes take no column.
static std::size_t columns(const std::string& text) {
  return static_cast<std::size_t>(std::ranges::count_if(
      text, [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
}

std::string table_text(const Table& t) {
  std::vector<std::size_t> width(t.header.size(), 0);
  auto measure = [&](const std::vector<std::string>& row) {
    for (std::size_t c = 0; c < row.size() && c < width.size(); ++c)
      width[c] = std::max(width[c], columns(row[c]));
  };
  measure(t.header);
  for (const auto& row : t.rows) measure(row);
  std::ostringstream s;
  auto line = [&](const std::vector<std::string>& row) {
    for (std::size_t c = 0; c < row.size() && c < width.size(); ++c) {
      const std::string pad(width[c] - columns(row[c]), ' ');
      const bool last = c + 1 == row.size();
      if (c > 0) s << "  ";
      if (c < t.numeric.size() && t.numeric[c]) {
        s << pad << row[c];
      } else {
        s << row[c] << (last ? "" : pad);
      }
    }
    s << "\n";
  };
  line(t.header);
  for (const auto& row : t.rows) line(row);
  return s.str();
}

}  // namespace detail

std::vector<fs::path> files_of_runs_chosen(const ReportInput& input,
                                           const std::vector<std::string>& selectors) {
  std::set<fs::path> files;
  for (const auto& selector : selectors) {
    for (const StoredRun* r : select(selector, input).runs) files.insert(r->path);
  }
  return {files.begin(), files.end()};
}

ReportInput load_report_inputs(const std::vector<fs::path>& paths) {
  ReportInput in;
  std::set<fs::path> seen;
  auto load_file = [&](const fs::path& p, bool named) {
    const fs::path canonical = fs::weakly_canonical(p);
    if (!seen.insert(canonical).second) return;
    try {
      const auto ext = p.extension().string();
      if (ext == ".yaml" || ext == ".yml") {
        in.published.push_back(import_benchmark_yaml(p));
        return;
      }
      if (ext != ".json") {
        if (named)
          throw ReportError(p.string() +
                            ": expected a results .json, an imported "
                            ".json or a benchmark.yaml");
        return;
      }
      std::ifstream f(p);
      const auto j = nlohmann::json::parse(f, nullptr, false);
      if (j.is_object() && j.contains("schema") && j["schema"] == kPublishedSchema) {
        in.published.push_back(published_from_json(j, p));
      } else {
        in.runs.push_back(load_run(p));
      }
    } catch (const ReportError& e) {
      if (named) throw;
      in.skipped.push_back(e.what());
    }
  };
  for (const auto& p : paths) {
    if (fs::is_directory(p)) {
      std::vector<fs::path> files;
      for (const auto& e : fs::recursive_directory_iterator(p)) {
        const auto name = e.path().filename().string();
        if ((may_be_run_file(e.path()) || may_be_imported_file(e.path()) ||
             name == "benchmark.yaml") &&
            is_regular_file_or_skip(e, in.skipped))
          files.push_back(e.path());
      }
      std::ranges::sort(files);
      for (const auto& f : files) load_file(f, false);
    } else if (fs::exists(p)) {
      load_file(p, true);
    } else {
      throw ReportError(p.string() + ": no such file or folder");
    }
  }
  sort_by_start(in.runs);
  return in;
}

}  // namespace robotperf::report
