#include "robotperf/report/gate.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "report_model.hpp"
#include "robotperf/report/run_store.hpp"
#include "robotperf/report/significance.hpp"

namespace robotperf::report {
namespace {

using Verdict = GateFinding::Verdict;
using Runs = std::vector<const StoredRun*>;

// A valid run whose answers were right: no functional check, or one that passed (the store
// reads a failed one as "INVALID: why").
bool usable(const StoredRun& r) {
  return r.valid && !r.functional.starts_with("INVALID");
}

std::optional<double> json_number(const nlohmann::json& j) {
  if (j.is_number()) return j.get<double>();
  return std::nullopt;
}

// One figure of a run, or nothing where the run has none.
struct Figure {
  std::string name, unit;
  bool smaller_is_better = true;
  std::function<std::optional<double>(const StoredRun&)> of;
};

std::vector<Figure> figures_of(const Runs& runs) {
  std::vector<Figure> out = {
      {"latency p50", "ms", true,
       [](const StoredRun& r) -> std::optional<double> {
         return std::isfinite(r.latency.p50) ? std::optional(r.latency.p50) : std::nullopt;
       }},
      {"latency p99", "ms", true,
       [](const StoredRun& r) -> std::optional<double> {
         return std::isfinite(r.latency.p99) ? std::optional(r.latency.p99) : std::nullopt;
       }},
      {"throughput", "Hz", false,
       [](const StoredRun& r) -> std::optional<double> {
         return std::isfinite(r.throughput_hz) ? std::optional(r.throughput_hz) : std::nullopt;
       }},
      {"energy per message", "mJ", true, [](const StoredRun& r) -> std::optional<double> {
         const auto& power = r.json.value("power", nlohmann::json::object());
         if (!power.is_object() || !power.contains("total") || !power["total"].is_object())
           return std::nullopt;
         return json_number(power["total"].value("energy_per_message_mj", nlohmann::json()));
       }}};
  // The functional metrics with a threshold: a maximum makes smaller better, a minimum larger.
  std::map<std::string, std::pair<std::string, bool>> functional;
  for (const StoredRun* r : runs) {
    const auto& f = r->json.value("functional", nlohmann::json());
    if (!f.is_object() || !f.contains("metrics") || !f["metrics"].is_object()) continue;
    for (const auto& [name, m] : f["metrics"].items()) {
      if (!m.is_object()) continue;
      const bool has_max = m.contains("max") && m["max"].is_number();
      const bool has_min = m.contains("min") && m["min"].is_number();
      if (has_max || has_min) functional[name] = {m.value("unit", ""), has_max};
    }
  }
  for (const auto& [name, how] : functional) {
    out.push_back({name, how.first, how.second, [name](const StoredRun& r) {
                     const auto& f = r.json.value("functional", nlohmann::json());
                     if (!f.is_object() || !f.contains("metrics") || !f["metrics"].is_object() ||
                         !f["metrics"].contains(name) || !f["metrics"][name].is_object())
                       return std::optional<double>();
                     return json_number(f["metrics"][name].value("value", nlohmann::json()));
                   }});
  }
  return out;
}

bool closed(const metrics::PercentileInterval& i) {
  return !std::isnan(i.lower) && !std::isnan(i.upper);
}

GateFinding judge(const std::string& id, const Figure& figure, const Runs& base, const Runs& cand,
                  double threshold_percent) {
  GateFinding f;
  f.benchmark = id;
  f.metric = figure.name;
  f.unit = figure.unit;
  std::vector<double> a, b;
  for (const StoredRun* r : base)
    if (const auto x = figure.of(*r)) a.push_back(*x);
  for (const StoredRun* r : cand)
    if (const auto x = figure.of(*r)) b.push_back(*x);
  f.baseline_runs = a.size();
  f.candidate_runs = b.size();
  if (a.empty() || b.empty()) return f;
  const auto sa = metrics::compute_stats(a), sb = metrics::compute_stats(b);
  f.baseline = sa.p50;
  f.candidate = sb.p50;
  f.baseline_interval = sa.p50_ci;
  f.candidate_interval = sb.p50_ci;
  f.change_percent = f.baseline != 0 ? 100.0 * (f.candidate - f.baseline) / f.baseline : 0;
  bool significant = false;
  if (closed(sa.p50_ci) && closed(sb.p50_ci)) {
    significant = sa.p50_ci.upper < sb.p50_ci.lower || sb.p50_ci.upper < sa.p50_ci.lower;
    f.basis = significant ? "the medians' 95 % intervals do not overlap"
                          : "the medians' 95 % intervals overlap";
  } else if (a.size() >= kGateMinRuns && b.size() >= kGateMinRuns) {
    const double p = welch_test(a, b).p_value;
    significant = p < kGateAlpha;
    std::ostringstream basis;
    basis << "Welch's test over the runs, p = " << format_fixed(p, 4);
    f.basis = basis.str();
  } else {
    f.basis = "too few valid runs to judge (" + std::to_string(a.size()) + " and " +
              std::to_string(b.size()) + "; at least " + std::to_string(kGateMinRuns) +
              " a side: --repeat)";
    return f;
  }
  const bool worse = figure.smaller_is_better ? f.candidate > f.baseline : f.candidate < f.baseline;
  if (!significant) {
    f.verdict = Verdict::kNoise;
  } else if (!worse) {
    f.verdict = Verdict::kImprovement;
  } else {
    f.verdict = std::fabs(f.change_percent) > threshold_percent ? Verdict::kRegression
                                                                : Verdict::kWorseWithin;
  }
  return f;
}

const char* verdict_word(Verdict v) {
  switch (v) {
    case Verdict::kRegression:
      return "REGRESSION";
    case Verdict::kWorseWithin:
      return "worse, within the threshold";
    case Verdict::kImprovement:
      return "better";
    case Verdict::kNoise:
      return "within noise";
    case Verdict::kNotJudged:
      return "not judged";
  }
  return "?";
}

std::string with_interval(const GateFinding& f, double median, const metrics::PercentileInterval& i,
                          std::size_t runs) {
  std::string out = format_fixed(median, 3) + " " + f.unit;
  if (closed(i)) out += " [" + format_fixed(i.lower, 3) + ", " + format_fixed(i.upper, 3) + "]";
  return out + " (" + std::to_string(runs) + " run" + (runs == 1 ? "" : "s") + ")";
}

std::string change_text(const GateFinding& f) {
  if (f.baseline_runs == 0 || f.candidate_runs == 0) return "";
  return (f.change_percent >= 0 ? "+" : "") + format_fixed(f.change_percent, 1) + " %";
}

std::string outcome_line(const GateResult& g) {
  const std::size_t n = g.regressions();
  if (n > 0)
    return "FAIL: " + std::to_string(n) + " regression" + (n == 1 ? "" : "s") + " beyond " +
           format_fixed(g.threshold_percent, 1) + " %";
  return "PASS: no significant regression beyond " + format_fixed(g.threshold_percent, 1) + " % (" +
         std::to_string(g.judged()) + " figures judged)";
}

}  // namespace

std::size_t GateResult::regressions() const {
  return static_cast<std::size_t>(std::ranges::count_if(
      findings, [](const GateFinding& f) { return f.verdict == Verdict::kRegression; }));
}

std::size_t GateResult::judged() const {
  return static_cast<std::size_t>(std::ranges::count_if(
      findings, [](const GateFinding& f) { return f.verdict != Verdict::kNotJudged; }));
}

GateResult run_gate(const ReportInput& input, const std::string& baseline,
                    const std::string& candidate, double threshold_percent) {
  GateResult g;
  g.baseline = baseline;
  g.candidate = candidate;
  g.threshold_percent = threshold_percent;
  const detail::Selection base = detail::select_runs(baseline, input);
  const detail::Selection cand = detail::select_runs(candidate, input);
  std::set<std::string> chosen = base.fields;
  chosen.insert(cand.fields.begin(), cand.fields.end());
  std::map<std::string, Runs> base_by_id, cand_by_id, cand_all_by_id;
  for (const StoredRun* r : base.runs)
    if (usable(*r)) base_by_id[r->benchmark_id].push_back(r);
  for (const StoredRun* r : cand.runs) {
    cand_all_by_id[r->benchmark_id].push_back(r);
    if (usable(*r)) cand_by_id[r->benchmark_id].push_back(r);
  }
  std::size_t shared = 0;
  for (const auto& [id, base_runs] : base_by_id) {
    if (!cand_all_by_id.contains(id)) continue;
    ++shared;
    // An INVALID candidate run (lost messages, wrong answers) where the baseline's were valid.
    const Runs& all = cand_all_by_id[id];
    const auto invalid = static_cast<std::size_t>(
        std::ranges::count_if(all, [](const StoredRun* r) { return !usable(*r); }));
    if (invalid > 0) {
      GateFinding f;
      f.benchmark = id;
      f.metric = "validity";
      f.verdict = Verdict::kRegression;
      f.baseline_runs = base_runs.size();
      f.candidate_runs = all.size();
      const StoredRun* first = *std::ranges::find_if(all, [](auto* r) { return !usable(*r); });
      f.basis = std::to_string(invalid) + " of " + std::to_string(all.size()) +
                " candidate runs INVALID (" + first->stem() + ": " +
                (first->valid ? first->functional : joined(first->invalid_reasons, "; ")) + ")";
      g.findings.push_back(f);
    }
    const Runs& cand_runs = cand_by_id[id];
    // Said once per benchmark: the first pair of runs that differ besides what was selected.
    const auto unlike_pair = [&]() -> std::vector<std::string> {
      for (const StoredRun* a : base_runs) {
        for (const StoredRun* b : cand_runs) {
          if (auto differ = detail::unlike(*a, *b, chosen); !differ.empty()) return differ;
        }
      }
      return {};
    };
    if (const auto differ = unlike_pair(); !differ.empty()) {
      g.notes.push_back(id + ": besides what was selected, baseline and candidate differ in " +
                        joined(differ, "; "));
    }
    Runs both = base_runs;
    both.insert(both.end(), cand_runs.begin(), cand_runs.end());
    for (const Figure& figure : figures_of(both)) {
      GateFinding f = judge(id, figure, base_runs, cand_runs, threshold_percent);
      if (figure.name == "throughput" && f.verdict != Verdict::kNotJudged) {
        // At two input rates an offered throughput is the input rate, not a result.
        const bool one_rate = std::ranges::all_of(both, [&](const StoredRun* r) {
          return std::fabs(r->rate_hz - both.front()->rate_hz) <= 1e-9 * both.front()->rate_hz;
        });
        if (!one_rate) {
          f.verdict = Verdict::kNotJudged;
          f.basis = "the input rates differ: an offered throughput is the rate fed, not a result";
        }
      }
      if (f.baseline_runs > 0 && f.candidate_runs > 0) g.findings.push_back(f);
    }
  }
  if (shared == 0)
    throw ReportError("the gate has nothing to judge: '" + baseline + "' and '" + candidate +
                      "' have no valid baseline run of a benchmark the candidate ran");
  return g;
}

std::string gate_text(const GateResult& g) {
  detail::Table t;
  t.header = {"benchmark",          "metric", "baseline (median)",
              "candidate (median)", "change", "verdict"};
  t.numeric = {false, false, true, true, true, false};
  for (const auto& f : g.findings) {
    t.rows.push_back({f.benchmark, f.metric,
                      f.metric == "validity"
                          ? std::string()
                          : with_interval(f, f.baseline, f.baseline_interval, f.baseline_runs),
                      f.metric == "validity"
                          ? std::string()
                          : with_interval(f, f.candidate, f.candidate_interval, f.candidate_runs),
                      f.metric == "validity" ? std::string() : change_text(f),
                      std::string(verdict_word(f.verdict)) + " (" + f.basis + ")"});
  }
  std::ostringstream out;
  out << "gate: candidate '" << g.candidate << "' against baseline '" << g.baseline
      << "'; fails on a significant change for the worse beyond "
      << format_fixed(g.threshold_percent, 1) << " %\n"
      << detail::table_text(t);
  for (const auto& n : g.notes) out << "note: " << n << "\n";
  out << "result: " << outcome_line(g) << "\n";
  return out.str();
}

std::string gate_markdown(const GateResult& g) {
  std::ostringstream out;
  out << "### robotperf gate: " << outcome_line(g) << "\n\n"
      << "Candidate `" << g.candidate << "` against baseline `" << g.baseline << "`.\n\n"
      << "| benchmark | metric | baseline (median) | candidate (median) | change | verdict |\n"
      << "|---|---|---:|---:|---:|---|\n";
  for (const auto& f : g.findings) {
    const bool validity = f.metric == "validity";
    out << "| " << f.benchmark << " | " << f.metric << " | "
        << (validity ? "" : with_interval(f, f.baseline, f.baseline_interval, f.baseline_runs))
        << " | "
        << (validity ? "" : with_interval(f, f.candidate, f.candidate_interval, f.candidate_runs))
        << " | " << (validity ? "" : change_text(f)) << " | "
        << (f.verdict == Verdict::kRegression ? "**REGRESSION**" : verdict_word(f.verdict)) << " ("
        << f.basis << ") |\n";
  }
  for (const auto& n : g.notes) out << "\n> " << n << "\n";
  return out.str();
}

std::string gate_junit(const GateResult& g) {
  std::ostringstream out;
  const std::size_t skipped = g.findings.size() - g.judged();
  out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      << "<testsuites name=\"robotperf gate\" tests=\"" << g.findings.size() << "\" failures=\""
      << g.regressions() << "\">\n"
      << "  <testsuite name=\"" << detail::html_escape(g.candidate + " vs " + g.baseline)
      << "\" tests=\"" << g.findings.size() << "\" failures=\"" << g.regressions()
      << "\" skipped=\"" << skipped << "\">\n";
  for (const auto& f : g.findings) {
    out << "    <testcase classname=\"" << detail::html_escape(f.benchmark) << "\" name=\""
        << detail::html_escape(f.metric) << "\">";
    const std::string what =
        f.metric == "validity"
            ? f.basis
            : f.metric + " " + change_text(f) + ": " +
                  with_interval(f, f.baseline, f.baseline_interval, f.baseline_runs) + " -> " +
                  with_interval(f, f.candidate, f.candidate_interval, f.candidate_runs) + "; " +
                  f.basis;
    if (f.verdict == Verdict::kRegression)
      out << "<failure message=\"" << detail::html_escape(what) << "\"/>";
    else if (f.verdict == Verdict::kNotJudged)
      out << "<skipped message=\"" << detail::html_escape(f.basis) << "\"/>";
    else
      out << "<system-out>" << detail::html_escape(what) << "</system-out>";
    out << "</testcase>\n";
  }
  out << "  </testsuite>\n</testsuites>\n";
  return out.str();
}

}  // namespace robotperf::report
