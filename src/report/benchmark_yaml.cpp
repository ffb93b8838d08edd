#include "robotperf/report/benchmark_yaml.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

#include "robotperf/files/yaml_scalar.hpp"

namespace robotperf::report {
namespace {

namespace fs = std::filesystem;

// RobotPerf's TEMPLATE.yaml order, used when a file has no entry to copy the order from.
constexpr std::array<const char*, 9> kDefaultOrder = {"type",     "metric",   "metric_unit",
                                                      "hardware", "category", "timestampt",
                                                      "value",    "note",     "datasource"};

std::string scalar_text(const YAML::Node& map, const char* key) {
  const YAML::Node n = map[key];
  return n.IsDefined() && n.IsScalar() ? n.Scalar() : std::string();
}

std::optional<double> parse_number(const std::string& text) {
  if (text.empty()) return std::nullopt;
  const char* begin = text.data();
  const char* end = begin + text.size();
  if (*begin == '+') ++begin;
  double v = 0;
  const auto [ptr, ec] = std::from_chars(begin, end, v);
  if (ec != std::errc() || ptr != end) return std::nullopt;
  return v;
}

std::string where(const fs::path& file, const YAML::Mark& mark) {
  return file.string() + (mark.line >= 0 ? ":" + std::to_string(mark.line + 1) : "");
}

// RobotPerf wrote some hardware names as plain YAML scalars holding a double-quoted string's
// escape ("ROBOTCORE\\xAE Perception"), which YAML leaves as four characters: the same platform
// would appear twice. Each "\\xHH" becomes the character U+00HH, in UTF-8.
std::string without_escapes(const std::string& text) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '\\' && i + 3 < text.size() && text[i + 1] == 'x' &&
        std::isxdigit(static_cast<unsigned char>(text[i + 2])) &&
        std::isxdigit(static_cast<unsigned char>(text[i + 3]))) {
      const auto code = static_cast<unsigned>(std::stoul(text.substr(i + 2, 2), nullptr, 16));
      if (code < 0x80) {
        out += static_cast<char>(code);
      } else {
        out += static_cast<char>(0xC0 | (code >> 6));
        out += static_cast<char>(0x80 | (code & 0x3F));
      }
      i += 3;
      continue;
    }
    out += text[i];
  }
  return out;
}

PublishedResult read_entry(const YAML::Node& item) {
  PublishedResult r;
  r.line = item.Mark().line >= 0 ? item.Mark().line + 1 : 0;
  // (Assigning to an existing YAML::Node would rebind the node inside the document.)
  const YAML::Node fields =
      item.IsMap() && item["result"].IsDefined() ? YAML::Node(item["result"]) : item;
  if (!fields.IsMap()) {
    r.flags.push_back("malformed entry: expected '- result:' with a mapping of fields");
    return r;
  }
  r.type = scalar_text(fields, "type");
  r.metric = scalar_text(fields, "metric");
  r.metric_unit = scalar_text(fields, "metric_unit");
  r.hardware = without_escapes(scalar_text(fields, "hardware"));
  r.category = scalar_text(fields, "category");
  r.timestampt = scalar_text(fields, "timestampt");
  r.value_text = scalar_text(fields, "value");
  r.value = parse_number(r.value_text).value_or(kNoValue);
  r.note = scalar_text(fields, "note");
  r.datasource = scalar_text(fields, "datasource");
  return r;
}

std::vector<PublishedResult> read_results(const YAML::Node& results, const fs::path& file) {
  std::vector<PublishedResult> out;
  if (!results.IsDefined() || results.IsNull()) return out;
  if (!results.IsSequence())
    throw ReportError(where(file, results.Mark()) + ": 'results' must be a list of '- result:'");
  for (const auto& item : results) out.push_back(read_entry(item));
  return out;
}

// RobotPerf's published format numbers its benchmarks within their category, the id's letter
// naming it (robotperf/benchmarks: a1-a5 are perception's, b1-b3 localization's, ...): data of
// that format, for a published file read outside its <category>/<package>/ folder. Empty for an
// id it does not number.
std::string published_category_of_id(const std::string& id) {
  static const std::map<char, std::string> kCategoryOfIdLetter = {
      {'a', "perception"},   {'b', "localization"}, {'c', "control"},
      {'d', "manipulation"}, {'m', "meta"},         {'n', "middleware"}};
  if (id.empty()) return {};
  const auto it = kCategoryOfIdLetter.find(id[0]);
  return it == kCategoryOfIdLetter.end() ? std::string() : it->second;
}

// The category of the package `file` lies in, when the caller named none: the folder above it
// (<category>/<package>/benchmark.yaml), as the harness records a loaded package's, for one of
// robotperf's packages (a graph.yaml beside the file); for a published RobotPerf file, which may
// be a copy anywhere, the category its id has in that format, else that folder. Empty where
// the path names no folder above the package.
std::string package_category(const fs::path& file, const std::string& id) {
  const fs::path package = file.parent_path();
  const std::string folder = package.has_parent_path()
                                 ? fs::absolute(package).parent_path().filename().string()
                                 : std::string();
  if (fs::exists(fs::absolute(file).parent_path() / "graph.yaml")) return folder;
  const std::string published = published_category_of_id(id);
  return published.empty() ? folder : published;
}

std::string render_entry(const PublishedResult& e, std::size_t dash_col, std::size_t field_col,
                         const std::vector<std::string>& order) {
  std::string out = std::string(dash_col, ' ') + "- result:\n";
  for (const auto& key : order) {
    std::string value;
    if (key == "type") value = files::yaml_scalar(e.type);
    if (key == "metric") value = files::yaml_scalar(e.metric);
    if (key == "metric_unit") value = files::yaml_scalar(e.metric_unit);
    if (key == "hardware") value = files::yaml_scalar(e.hardware);
    if (key == "category") value = files::yaml_scalar(e.category);
    if (key == "timestampt") value = files::yaml_scalar(e.timestampt);
    if (key == "value")
      value = std::isfinite(e.value) ? shortest_number(e.value) : files::yaml_scalar(e.value_text);
    if (key == "note") value = files::yaml_scalar(e.note);
    if (key == "datasource") value = files::yaml_scalar(e.datasource);
    out += std::string(field_col, ' ') + key + ": " + value + "\n";
  }
  return out;
}

std::vector<std::string> default_order() {
  return {kDefaultOrder.begin(), kDefaultOrder.end()};
}

std::string fmt(const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

}  // namespace

std::string PublishedResult::stated_rate() const {
  if (!note_rate_hz) return "";
  const auto [low, high] = *note_rate_hz;
  return low == high ? fmt("%g Hz", low) : fmt("%g", low) + fmt("-%g Hz sweep", high);
}

bool PublishedResult::same_entry(const PublishedResult& o) const {
  const bool same_value =
      (std::isnan(value) && std::isnan(o.value) && value_text == o.value_text) || value == o.value;
  return same_value && type == o.type && metric == o.metric && metric_unit == o.metric_unit &&
         hardware == o.hardware && category == o.category && timestampt == o.timestampt &&
         note == o.note && datasource == o.datasource;
}

std::size_t PublishedBenchmark::flagged() const {
  return static_cast<std::size_t>(
      std::ranges::count_if(results, [](const auto& r) { return !r.flags.empty(); }));
}

std::string shortest_number(double value) {
  char buf[64];
  const auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, value);
  std::string s(buf, ec == std::errc() ? ptr : buf);
  // A whole number keeps a decimal point, so that YAML readers see a float as RobotPerf writes.
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";
  return s;
}

void check_published(PublishedResult& r) {
  r.flags.erase(std::remove_if(r.flags.begin(), r.flags.end(),
                               [](const std::string& f) { return !f.starts_with("malformed"); }),
                r.flags.end());
  static const std::regex figure(
      "\\b(mean|rms|min|max)(?:_benchmark|_latency)?\\s*:?\\s*(-?[0-9]+(?:\\.[0-9]+)?(?:[eE][-+]?["
      "0-9]+)?)",
      std::regex::icase);
  static const std::regex loss(
      "(?:lost messages|frames lost|lost)\\s*:?\\s*(-?[0-9]+(?:\\.[0-9]+)?)"
      "\\s*%",
      std::regex::icase);
  for (std::sregex_iterator it(r.note.begin(), r.note.end(), figure), end; it != end; ++it) {
    std::string name = (*it)[1].str();
    std::ranges::transform(name, name.begin(), [](unsigned char c) { return std::tolower(c); });
    // A figure beyond double's range (from_chars refuses it) is flagged, not taken.
    const auto parsed = parse_number((*it)[2].str());
    if (!parsed) {
      r.flags.push_back("the note's " + name + " (" + (*it)[2].str() + ") is not a number");
      continue;
    }
    const double v = *parsed;
    auto& slot = name == "mean"  ? r.note_mean
                 : name == "rms" ? r.note_rms
                 : name == "min" ? r.note_min
                                 : r.note_max;
    if (!slot) slot = v;
    if (v < 0) {
      r.flags.push_back("negative " + name + (r.metric == "latency" ? " latency" : "") +
                        " in the note (" + fmt("%g", v) + ")");
    }
  }
  // A sweep first: its upper end would otherwise read as a stated rate ("... to 300 fps").
  static const std::regex sweep(
      "([0-9]+(?:\\.[0-9]+)?)\\s*(?:-|to)\\s*([0-9]+(?:\\.[0-9]+)?)\\s*(?:fps|hz)\\b",
      std::regex::icase);
  static const std::regex rate(
      "(?:bounded to|fixed at|\\bat|\\brate)\\s+([0-9]+(?:\\.[0-9]+)?)\\s*(?:fps|hz)\\b",
      std::regex::icase);
  std::smatch m;
  r.note_rate_hz.reset();
  if (std::regex_search(r.note, m, sweep)) {
    const auto low = parse_number(m[1].str()), high = parse_number(m[2].str());
    if (low && high && *low > 0 && *low <= *high) r.note_rate_hz = std::pair{*low, *high};
  } else if (std::regex_search(r.note, m, rate)) {
    if (const auto hz = parse_number(m[1].str()); hz && *hz > 0)
      r.note_rate_hz = std::pair{*hz, *hz};
  }
  if (std::regex_search(r.note, m, loss)) {
    r.note_loss_percent = parse_number(m[1].str());
    if (!r.note_loss_percent) {
      r.flags.push_back("the note's loss (" + m[1].str() + " %) is not a number");
    } else if (*r.note_loss_percent > 100.0) {
      r.flags.push_back("loss " + m[1].str() +
                        " % is above 100 % (lost messages counted by position, not by ID)");
    } else if (*r.note_loss_percent < 0) {
      r.flags.push_back("negative loss " + m[1].str() + " %");
    }
  }
  if (!std::isfinite(r.value)) {
    r.flags.push_back(r.value_text.empty() ? "no value"
                                           : "value '" + r.value_text + "' is not a number");
    return;
  }
  if (r.metric == "latency" && r.value < 0)
    r.flags.push_back("negative latency " + fmt("%g", r.value) + " " + r.metric_unit);
  if (r.metric == "latency" && r.value == 0) r.flags.push_back("zero latency");
  if (r.metric == "throughput" && r.value <= 0)
    r.flags.push_back("throughput " + fmt("%g", r.value) + " <= 0");
  if (r.metric == "power") {
    if (r.value <= 0) {
      r.flags.push_back("power " + fmt("%g", r.value) +
                        " W <= 0: no sensor was read (should be 'unavailable')");
    } else if (r.value < 1e-3) {
      r.flags.push_back("power " + fmt("%g", r.value) +
                        " W is below 1 mW: not a sensor reading (uninitialised memory?)");
    }
  }
}

PublishedBenchmark import_benchmark_yaml(const fs::path& path_in, const std::string& category) {
  fs::path path = fs::is_directory(path_in) ? path_in / "benchmark.yaml" : path_in;
  if (!fs::exists(path)) throw ReportError(path.string() + ": no such benchmark.yaml");
  YAML::Node root;
  try {
    root = YAML::LoadFile(path.string());
  } catch (const YAML::Exception& e) {
    throw ReportError(where(path, e.mark) + ": malformed YAML: " + e.msg);
  }
  if (!root.IsMap())
    throw ReportError(path.string() +
                      ": not a benchmark.yaml (expected a mapping with id, name, "
                      "results)");
  // yaml-cpp's own exceptions (a mapping where a scalar belongs, say) become one line naming the
  // file.
  try {
    PublishedBenchmark b;
    b.source = path;
    b.id = scalar_text(root, "id");
    b.name = scalar_text(root, "name");
    if (b.id.empty() && b.name.empty())
      throw ReportError(path.string() + ": not a benchmark.yaml (no 'id' or 'name')");
    if (b.id.empty()) b.id = b.name.substr(0, b.name.find('_'));
    b.short_description = scalar_text(root, "short");
    b.description = scalar_text(root, "description");
    b.graph = scalar_text(root, "graph");
    b.reproduction = scalar_text(root, "reproduction");
    b.category = category.empty() ? package_category(path, b.id) : category;
    b.results = read_results(root["results"], path);
    for (auto& r : b.results) check_published(r);
    return b;
  } catch (const YAML::Exception& e) {
    throw ReportError(where(path, e.mark) + ": unexpected YAML structure: " + e.msg);
  }
}

std::vector<PublishedResult> export_entries(const StoredRun& run, const ExportOptions& options) {
  PublishedResult base;
  base.type = run.type.empty() ? "black" : run.type;
  base.hardware = options.hardware.empty() ? run.hardware : options.hardware;
  base.category = options.category.empty() ? run.hardware_category : options.category;
  base.timestampt = run.timestamp();
  base.datasource = run.dataset;
  const std::string lost = "lost " + format_fixed(run.loss_percent, 2) + " % (" +
                           std::to_string(run.lost) + " of " + std::to_string(run.measured) + ")";
  // Worded as check_published reads a rate back ("input rate 30.0 Hz"), so that an exported row
  // is matched on its rate as RobotPerf's own are. A peak search states no rate it was fed at.
  const bool peak = run.throughput_kind == "peak";
  // The entry names its benchmark and configuration: a folder's exported entries all come from
  // one dataset name, which says neither.
  std::string context =
      "benchmark " + run.benchmark_id + ", " +
      (peak ? "peak search (the highest input rate that met its bounds: " +
                  format_fixed(run.rate_hz, 1) + " Hz)"
            : "input rate " + format_fixed(run.rate_hz, 1) + " Hz") +
      ", rmw " + run.rmw + ", " + run.processes +
      (run.processes == "single" ? " process" : " processes") +
      (run.backend.empty() || run.backend == "cpu" ? "" : ", backend " + run.backend) +
      ", robotperf " + run.robotperf_version + " (" + run.git_revision + ")";
  for (const auto& [key, value] : run.labels) {
    if (!key.starts_with("robotperf.")) context += ", label " + key + "=" + value;
  }
  if (!run.valid) {
    std::string why;
    for (const auto& r : run.invalid_reasons) why += (why.empty() ? "" : "; ") + r;
    context += ", INVALID result: " + why;
  }
  // An output's jitter, when the run recorded it: ", output jitter ..." or "".
  auto jitter = [](const StoredOutput& o) -> std::string {
    if (o.jitter.count == 0) return "";
    return ", output jitter |interval - period| mean " + format_fixed(o.jitter.mean, 3) +
           " ms, p99 " + format_fixed(o.jitter.p99, 3) + " ms, max " +
           format_fixed(o.jitter.max, 3) + " ms against the input period " +
           format_fixed(o.period_ms, 3) + " ms";
  };
  auto latency_note = [](const LatencySummary& l) {
    return "mean " + format_fixed(l.mean, 3) + " ms, rms " + format_fixed(l.rms, 3) + " ms, max " +
           format_fixed(l.max, 3) + " ms, min " + format_fixed(l.min, 3) + " ms, p50 " +
           format_fixed(l.p50, 3) + " ms, p99 " + format_fixed(l.p99, 3) + " ms, ";
  };
  std::vector<PublishedResult> out;
  if (std::isfinite(run.latency.max)) {
    PublishedResult e = base;
    e.metric = "latency";
    e.metric_unit = "ms";
    e.value = run.latency.max;
    e.note = latency_note(run.latency) + lost +
             (run.outputs.empty() ? "" : jitter(run.outputs.front())) +
             ", from the scheduled send, " + context;
    out.push_back(std::move(e));
  }
  // A graph's further outputs (graph.yaml `outputs:`): a latency row each, named in its note.
  for (std::size_t i = 1; i < run.outputs.size(); ++i) {
    const StoredOutput& o = run.outputs[i];
    if (!std::isfinite(o.latency.max)) continue;
    PublishedResult e = base;
    e.metric = "latency";
    e.metric_unit = "ms";
    e.value = o.latency.max;
    e.note = "output " + o.topic + ": " + latency_note(o.latency) + "lost " +
             format_fixed(o.loss_percent, 2) + " %" + jitter(o) + ", from the scheduled send, " +
             context;
    out.push_back(std::move(e));
  }
  if (std::isfinite(run.throughput_hz) && run.throughput_hz > 0) {
    PublishedResult e = base;
    e.metric = "throughput";
    e.metric_unit = "fps";
    e.value = run.throughput_hz;
    // docs/design.md §3.5: a throughput says whether it is offered-bounded or a peak.
    e.note = (peak ? "peak output rate" : "offered-bounded output rate") +
             std::string(", offered ") + format_fixed(run.offered_hz, 3) + " Hz, " + lost + ", " +
             context;
    out.push_back(std::move(e));
  }
  if (run.power_w) {
    PublishedResult e = base;
    e.metric = "power";
    e.metric_unit = "W";
    e.value = *run.power_w;
    e.note = "average over the measured window";
    if (run.energy_j) e.note += ", energy " + format_fixed(*run.energy_j, 3) + " J";
    if (!run.power_note.empty()) e.note += ", source " + run.power_note;
    e.note += ", " + context;
    out.push_back(std::move(e));
  }
  for (auto& e : out) e.value_text = shortest_number(e.value);
  return out;
}

std::string entries_yaml(const std::vector<PublishedResult>& entries) {
  std::string out = "results:\n";
  for (const auto& e : entries) out += render_entry(e, 0, 4, default_order());
  return out;
}

MergeOutcome merge_entries(const std::string& original, const std::string& name,
                           const std::vector<PublishedResult>& entries) {
  YAML::Node root;
  try {
    root = YAML::Load(original);
  } catch (const YAML::Exception& e) {
    throw ReportError(where(name, e.mark) + ": malformed YAML: " + e.msg);
  }
  if (!root.IsMap()) throw ReportError(name + ": not a benchmark.yaml (expected a mapping)");

  // Line starts, and the top-level keys with their lines.
  std::vector<std::size_t> line_start = {0};
  for (std::size_t i = 0; i < original.size(); ++i) {
    if (original[i] == '\n') line_start.push_back(i + 1);
  }
  auto line_text = [&](int line) {
    const std::size_t b = line_start[static_cast<std::size_t>(line)];
    const std::size_t e = original.find('\n', b);
    return original.substr(b, e == std::string::npos ? std::string::npos : e - b);
  };
  int results_line = -1;
  YAML::Node results;
  std::vector<int> key_lines;
  for (const auto& kv : root) {
    key_lines.push_back(kv.first.Mark().line);
    if (kv.first.Scalar() == "results") {
      results_line = kv.first.Mark().line;
      results = kv.second;
    }
  }
  const std::vector<PublishedResult> existing = read_results(results, name);

  MergeOutcome outcome;
  std::vector<PublishedResult> to_add;
  for (const auto& e : entries) {
    const auto same = [&](const PublishedResult& x) { return x.same_entry(e); };
    if (std::ranges::any_of(existing, same) || std::ranges::any_of(to_add, same)) {
      ++outcome.already_present;
    } else {
      to_add.push_back(e);
    }
  }
  outcome.added = to_add.size();
  if (to_add.empty()) {
    outcome.text = original;
    return outcome;
  }

  std::string text;
  if (results_line < 0) {
    text = original;
    if (!text.empty() && text.back() != '\n') text += '\n';
    text += "results:\n";
    for (const auto& e : to_add) text += render_entry(e, 0, 4, default_order());
  } else if (existing.empty()) {
    static const std::regex empty_value("results:\\s*(\\[\\s*\\]|~|null)?\\s*(#.*)?\\r?");
    if (!std::regex_match(line_text(results_line), empty_value))
      throw ReportError(name + ":" + std::to_string(results_line + 1) +
                        ": cannot merge: write the empty results as 'results: []'");
    const std::size_t begin = line_start[static_cast<std::size_t>(results_line)];
    const std::size_t eol = original.find('\n', begin);
    text = original.substr(0, begin) + "results:\n";
    for (const auto& e : to_add) text += render_entry(e, 0, 4, default_order());
    if (eol != std::string::npos) text += original.substr(eol + 1);
  } else {
    if (results.Style() == YAML::EmitterStyle::Flow)
      throw ReportError(name + ":" + std::to_string(results_line + 1) +
                        ": cannot merge into a flow-style 'results: [...]'; write it as a block "
                        "list ('- result:' lines)");
    // Indentation and key order of the first existing entry.
    const YAML::Node first = results[0];
    const std::size_t key_col = static_cast<std::size_t>(first.Mark().column);
    const std::string first_line = line_text(first.Mark().line);
    const std::size_t dash = first_line.rfind('-', key_col);
    const std::size_t dash_col = dash == std::string::npos ? 0 : dash;
    std::size_t field_col = key_col + 2;
    std::vector<std::string> order;
    if (first.IsMap() && first["result"].IsMap()) {
      const YAML::Node fields = first["result"];
      if (fields.Style() == YAML::EmitterStyle::Block && fields.Mark().column > 0)
        field_col = static_cast<std::size_t>(fields.Mark().column);
      for (const auto& kv : fields) {
        const std::string k = kv.first.Scalar();
        if (std::ranges::find(kDefaultOrder, k) != kDefaultOrder.end()) order.push_back(k);
      }
    }
    for (const char* k : kDefaultOrder) {
      if (std::ranges::find(order, k) == order.end()) order.push_back(k);
    }
    // Insert after the last entry: before the next top-level key (and the comments and blank
    // lines that precede it), else at the end of the file.
    int next_key = -1;
    for (int l : key_lines) {
      if (l > results_line && (next_key < 0 || l < next_key)) next_key = l;
    }
    std::size_t insert_at = original.size();
    if (next_key >= 0) {
      int l = next_key;
      const int last_entry_line = results[results.size() - 1].Mark().line;
      while (l - 1 > last_entry_line) {
        const std::string t = line_text(l - 1);
        if (t.find_first_not_of(" \t\r") != std::string::npos && !t.starts_with("#")) break;
        --l;
      }
      insert_at = line_start[static_cast<std::size_t>(l)];
    }
    text = original.substr(0, insert_at);
    if (!text.empty() && text.back() != '\n') text += '\n';
    for (const auto& e : to_add) text += render_entry(e, dash_col, field_col, order);
    text += original.substr(insert_at);
  }

  // Check what would be written: the old entries unchanged and in place, the new ones after them
  // exactly as given, every other key untouched.
  YAML::Node merged;
  try {
    merged = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw ReportError(name + ": merging would produce malformed YAML (" + e.msg +
                      "); the file was not changed");
  }
  const auto after = read_results(merged["results"], name);
  bool ok = after.size() == existing.size() + to_add.size();
  for (std::size_t i = 0; ok && i < existing.size(); ++i) ok = after[i].same_entry(existing[i]);
  for (std::size_t i = 0; ok && i < to_add.size(); ++i)
    ok = after[existing.size() + i].same_entry(to_add[i]);
  for (const auto& kv : root) {
    if (!ok || kv.first.Scalar() == "results") continue;
    ok = YAML::Dump(kv.second) == YAML::Dump(merged[kv.first.Scalar()]);
  }
  if (!ok)
    throw ReportError(name +
                      ": merging would change existing content (unusual layout); the file "
                      "was not changed");
  outcome.text = std::move(text);
  return outcome;
}

nlohmann::json to_json(const PublishedBenchmark& b) {
  nlohmann::json results = nlohmann::json::array();
  for (const auto& r : b.results) {
    results.push_back({{"type", r.type},
                       {"metric", r.metric},
                       {"metric_unit", r.metric_unit},
                       {"hardware", r.hardware},
                       {"category", r.category},
                       {"timestampt", r.timestampt},
                       {"value", std::isfinite(r.value) ? nlohmann::json(r.value) : nullptr},
                       {"value_text", r.value_text},
                       {"note", r.note},
                       {"datasource", r.datasource},
                       {"line", r.line},
                       {"flags", r.flags}});
  }
  return {{"schema", kPublishedSchema},
          {"source", b.source.string()},
          {"id", b.id},
          {"name", b.name},
          {"short", b.short_description},
          {"description", b.description},
          {"graph", b.graph},
          {"reproduction", b.reproduction},
          {"category", b.category},
          {"results", results}};
}

PublishedBenchmark published_from_json(const nlohmann::json& j, const fs::path& from) {
  if (!j.is_object() || !j.contains("schema") || j.at("schema") != kPublishedSchema)
    throw ReportError(from.string() + ": not an imported benchmark file (expected \"schema\": \"" +
                      kPublishedSchema + "\")");
  try {
    PublishedBenchmark b;
    b.source = j.at("source").get<std::string>();
    b.id = j.at("id").get<std::string>();
    b.name = j.value("name", "");
    b.short_description = j.value("short", "");
    b.description = j.value("description", "");
    b.graph = j.value("graph", "");
    b.reproduction = j.value("reproduction", "");
    b.category = j.value("category", "");
    for (const auto& e : j.at("results")) {
      PublishedResult r;
      r.type = e.value("type", "");
      r.metric = e.value("metric", "");
      r.metric_unit = e.value("metric_unit", "");
      r.hardware = e.value("hardware", "");
      r.category = e.value("category", "");
      r.timestampt = e.value("timestampt", "");
      r.value = e.at("value").is_number() ? e["value"].get<double>() : kNoValue;
      r.value_text = e.value("value_text", "");
      r.note = e.value("note", "");
      r.datasource = e.value("datasource", "");
      r.line = e.value("line", 0);
      for (const auto& f : e.value("flags", nlohmann::json::array()))
        if (f.get<std::string>().starts_with("malformed")) r.flags.push_back(f);
      check_published(r);
      b.results.push_back(std::move(r));
    }
    return b;
  } catch (const nlohmann::json::exception& e) {
    throw ReportError(from.string() + ": broken imported benchmark file: " + e.what());
  }
}

std::string flagged_rows_report(const PublishedBenchmark& b) {
  std::ostringstream out;
  for (const auto& r : b.results) {
    if (r.flags.empty()) continue;
    out << b.source.string() << ":" << r.line << ": " << r.hardware << " · " << r.metric << " "
        << (r.value_text.empty() ? "?" : r.value_text) << " " << r.metric_unit << ": ";
    for (std::size_t i = 0; i < r.flags.size(); ++i) out << (i ? "; " : "") << r.flags[i];
    out << "\n";
  }
  return out.str();
}

}  // namespace robotperf::report
