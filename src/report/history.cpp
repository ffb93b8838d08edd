#include "robotperf/report/history.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>

#include "report_model.hpp"
#include "robotperf/metrics/latency_stats.hpp"

namespace robotperf::report {

namespace {

// The configuration of a run as a series of its history: the report's series name without the
// labels, which mark what changes along a history (a revision, a build) as often as what splits
// it (the CLI chooses runs by label; --system names the machine).
std::string series_of(StoredRun run) {
  run.labels.clear();
  return detail::local_series(run);
}

std::string revision_of(const StoredRun& run) {
  if (const auto it = run.labels.find("package.revision"); it != run.labels.end())
    return it->second;
  if (const auto it = run.labels.find("robotperf.revision"); it != run.labels.end())
    return it->second;
  return run.git_revision;
}

struct Measured {
  const StoredRun* run;
  RunMetric metric;
};

// The points of one configuration's runs (in start order): a point per run, or per --by value.
std::vector<HistoryPoint> points_of(const std::vector<Measured>& runs, const std::string& by) {
  std::vector<HistoryPoint> points;
  std::map<std::string, std::size_t> point_of_value;
  std::vector<std::vector<double>> values;
  for (const Measured& m : runs) {
    std::size_t i = points.size();
    if (!by.empty()) {
      const std::string& value = m.run->labels.at(by);
      const auto [it, added] = point_of_value.emplace(value, points.size());
      i = it->second;
      if (added) {
        HistoryPoint p;
        p.started_utc = m.run->started_utc;
        p.revision = value;
        points.push_back(std::move(p));
      }
    } else {
      HistoryPoint p;
      p.started_utc = m.run->started_utc;
      p.revision = revision_of(*m.run);
      points.push_back(std::move(p));
    }
    if (i == values.size()) values.emplace_back();
    values[i].push_back(m.metric.value);
    points[i].files.push_back(m.run->path.filename().string());
    if (points[i].runs++ == 0) {
      points[i].low = m.metric.low;
      points[i].high = m.metric.high;
    }
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    points[i].value = metrics::median(values[i]);
    if (values[i].size() > 1) {
      const auto [low, high] = std::minmax_element(values[i].begin(), values[i].end());
      points[i].low = *low;
      points[i].high = *high;
    }
  }
  return points;
}

std::string better_phrase(RunMetric::Better better) {
  const std::string which = better_text(better);
  return which.empty() ? "no better direction" : which + " is better";
}

// "worse", "better" or "" for a change of the figure by `percent`.
std::string judgement(RunMetric::Better better, double percent) {
  if (better == RunMetric::Better::kUnknown || !std::isfinite(percent)) return "";
  return (percent > 0) == (better == RunMetric::Better::kSmaller) ? "worse" : "better";
}

std::string interval_text(const HistoryPoint& p) {
  if (!std::isfinite(p.low) && !std::isfinite(p.high)) return "-";
  return detail::format_value(p.low) + " .. " + detail::format_value(p.high);
}

// "2026-11-22T07:42:22Z" as "2026-11-22 07:42:22".
std::string when(const std::string& utc) {
  std::string out = utc;
  if (out.size() >= 19 && out[10] == 'T') out[10] = ' ';
  if (!out.empty() && out.back() == 'Z') out.pop_back();
  return out;
}

}  // namespace

std::string short_revision(const std::string& revision, std::size_t digits) {
  const bool hash =
      revision.size() >= 20 && std::all_of(revision.begin(), revision.end(), [](char c) {
        return std::isxdigit(static_cast<unsigned char>(c)) != 0;
      });
  return hash ? revision.substr(0, digits) : revision;
}

MetricSource metrics_from_files(const std::vector<StoredRun>& runs) {
  return {[](const StoredRun& run, const std::string& name) { return run_metric(run, name); },
          [&runs](const std::string& benchmark_id) {
            std::set<std::string> names;
            for (const StoredRun& run : runs) {
              if (run.benchmark_id != benchmark_id) continue;
              for (const RunMetric& m : run_metrics(run)) {
                if (std::isfinite(m.value)) names.insert(m.name);
              }
            }
            return std::vector<std::string>(names.begin(), names.end());
          }};
}

History history(const std::vector<StoredRun>& runs, const HistoryOptions& options) {
  return history(runs, options, metrics_from_files(runs));
}

History history(const std::vector<StoredRun>& runs, const HistoryOptions& options,
                const MetricSource& source) {
  History out;
  out.benchmark_id = options.benchmark_id;
  out.metric = options.metric;
  out.by = options.by;
  out.change_points = options.change_points;
  std::map<std::string, std::vector<Measured>> by_series;
  std::size_t of_benchmark = 0, with_metric = 0, invalid = 0, unlabelled = 0;
  for (const StoredRun& run : runs) {
    if (run.benchmark_id != options.benchmark_id) continue;
    ++of_benchmark;
    std::optional<RunMetric> metric = source.of(run, options.metric);
    if (!metric) continue;
    ++with_metric;
    if (!run.valid) {
      ++invalid;
      continue;
    }
    if (!options.by.empty() && !run.labels.contains(options.by)) {
      ++unlabelled;
      continue;
    }
    out.unit = metric->unit;
    out.better = metric->better;
    by_series[series_of(run)].push_back({&run, std::move(*metric)});
  }
  if (of_benchmark == 0)
    throw ReportError("history: no runs of " + options.benchmark_id + " in the results read");
  if (with_metric == 0) {
    std::string known;
    for (const auto& n : source.names(options.benchmark_id))
      known += (known.empty() ? "" : ", ") + n;
    throw ReportError("history: no run of " + options.benchmark_id + " has the metric " +
                      options.metric + "; its runs have: " + known);
  }
  if (by_series.empty())
    throw ReportError("history: no valid run of " + options.benchmark_id + " has " +
                      options.metric + " (" + std::to_string(invalid) + " INVALID, " +
                      std::to_string(unlabelled) + " without the label " +
                      (options.by.empty() ? "asked for" : options.by) + ")" +
                      (invalid ? ": `robotperf results list` shows why runs are INVALID" : ""));
  if (invalid) out.notes.push_back(std::to_string(invalid) + " INVALID run(s) left out");
  if (unlabelled)
    out.notes.push_back(std::to_string(unlabelled) + " run(s) without the label " + options.by +
                        " left out");
  for (auto& [name, measured] : by_series) {
    std::stable_sort(measured.begin(), measured.end(), [](const Measured& a, const Measured& b) {
      return a.run->started_utc < b.run->started_utc;
    });
    HistorySeries series{name, points_of(measured, options.by), {}};
    std::vector<double> values;
    for (const auto& p : series.points) values.push_back(p.value);
    series.changes = change_points(values, options.change_points);
    out.series.push_back(std::move(series));
  }
  return out;
}

std::string history_text(const History& h) {
  std::ostringstream s;
  std::size_t runs = 0;
  for (const auto& series : h.series) {
    for (const auto& p : series.points) runs += p.runs;
  }
  s << h.benchmark_id << " " << h.metric << " (" << h.unit << ", " << better_phrase(h.better)
    << "): " << runs << " valid run(s) in " << h.series.size() << " configuration(s)";
  if (!h.by.empty()) s << ", one point per value of " << h.by;
  s << "\n";
  for (const auto& note : h.notes) s << "  " << note << "\n";
  for (const auto& series : h.series) {
    s << "\n" << series.name << "\n";
    detail::Table t;
    t.header = {"#",    "started (UTC)", h.by.empty() ? "revision" : h.by,
                "runs", h.metric,        h.by.empty() ? "95 % interval" : "interval or range",
                ""};
    t.numeric = {true, false, false, true, true, false, false};
    std::size_t next_change = 0;
    for (std::size_t i = 0; i < series.points.size(); ++i) {
      const HistoryPoint& p = series.points[i];
      std::string mark;
      if (next_change < series.changes.size() && series.changes[next_change].index == i) {
        const ChangePoint& c = series.changes[next_change++];
        const double percent = c.change_percent();
        char text[160];
        std::snprintf(text, sizeof text, "<- change: %s -> %s, %+.1f %% %s (p = %.3g)",
                      detail::format_value(c.before).c_str(), detail::format_value(c.after).c_str(),
                      percent, judgement(h.better, percent).c_str(), c.p_value);
        mark = text;
      }
      t.rows.push_back({std::to_string(i + 1), when(p.started_utc), short_revision(p.revision, 10),
                        std::to_string(p.runs), detail::format_value(p.value), interval_text(p),
                        mark});
    }
    if (series.changes.empty()) {  // no change column: nothing to say in it
      t.header.pop_back();
      t.numeric.pop_back();
      for (auto& row : t.rows) row.pop_back();
    }
    s << detail::table_text(t);
    if (series.changes.empty()) s << "no change point\n";
  }
  const double percent = h.change_points.significance * 100;
  s << "\nChange points: E-divisive means (Matteson & James 2014), each kept when a permutation "
       "test ("
    << h.change_points.permutations << " permutations) gives p <= " << h.change_points.significance
    << ": a series without a change shows one in about " << percent << " % of cases.\n";
  return s.str();
}

nlohmann::json history_json(const History& h) {
  nlohmann::json series = nlohmann::json::array();
  for (const auto& sr : h.series) {
    nlohmann::json points = nlohmann::json::array();
    for (const auto& p : sr.points) {
      auto number = [](double v) {
        return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json();
      };
      points.push_back({{"started_utc", p.started_utc},
                        {"revision", p.revision},
                        {"runs", p.runs},
                        {"value", number(p.value)},
                        {"low", number(p.low)},
                        {"high", number(p.high)},
                        {"files", p.files}});
    }
    nlohmann::json changes = nlohmann::json::array();
    for (const auto& c : sr.changes) {
      changes.push_back(
          {{"index", c.index},
           {"p_value", c.p_value},
           {"before", c.before},
           {"after", c.after},
           {"change_percent", std::isfinite(c.change_percent()) ? nlohmann::json(c.change_percent())
                                                                : nlohmann::json()}});
    }
    series.push_back({{"name", sr.name}, {"points", points}, {"changes", changes}});
  }
  return {{"benchmark", h.benchmark_id},
          {"metric", h.metric},
          {"unit", h.unit},
          {"better", h.better == RunMetric::Better::kSmaller  ? "smaller"
                     : h.better == RunMetric::Better::kLarger ? "larger"
                                                              : nlohmann::json()},
          {"by", h.by.empty() ? nlohmann::json() : nlohmann::json(h.by)},
          {"series", series},
          {"notes", h.notes},
          {"change_point_method",
           {{"name", "E-divisive means (Matteson & James 2014)"},
            {"significance", h.change_points.significance},
            {"permutations", h.change_points.permutations},
            {"min_segment", h.change_points.min_segment}}}};
}

}  // namespace robotperf::report
