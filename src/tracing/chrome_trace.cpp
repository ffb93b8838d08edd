// A trace's timeline as Chrome Trace Event JSON (`robotperf trace export`), which Perfetto UI
// and chrome://tracing open. Written as a stream: a timeline has millions of events.
#include <cinttypes>
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "robotperf/tracing/analysis.hpp"

namespace robotperf::tracing {

namespace {

// Microseconds (the format's unit) with the nanoseconds kept, from the trace's first event.
std::string micros(int64_t ns) {
  char buf[48];
  const char* sign = ns < 0 ? "-" : "";
  const uint64_t v = ns < 0 ? static_cast<uint64_t>(-(ns + 1)) + 1 : static_cast<uint64_t>(ns);
  std::snprintf(buf, sizeof buf, "%s%" PRIu64 ".%03" PRIu64, sign, v / 1000, v % 1000);
  return buf;
}

std::string json_string(const std::string& s) {
  return nlohmann::json(s).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace

void write_chrome_trace(const TraceAnalysis& a, std::ostream& out) {
  const int64_t origin = a.first_ns;
  out << "{\"displayTimeUnit\":\"ns\",\"otherData\":{\"generator\":\"robotperf trace export\","
         "\"trace_clock_origin_ns\":"
      << origin << "},\"traceEvents\":[\n";
  bool first = true;
  auto begin_event = [&] {
    if (!first) out << ",\n";
    first = false;
  };
  // Processes and threads named after the nodes whose callbacks ran on them.
  std::map<std::pair<int32_t, int32_t>, std::set<std::string>> thread_nodes;
  std::set<int32_t> processes;
  for (const TimelineEvent& e : a.timeline) {
    processes.insert(e.pid);
    if (e.kind == TimelineEvent::Kind::kCallback) thread_nodes[{e.pid, e.tid}].insert(e.node);
  }
  for (const int32_t pid : processes) {
    begin_event();
    std::string name = "process " + std::to_string(pid);
    if (a.run && a.run->pid == pid) name += " (robotperf " + a.run->benchmark + ")";
    out << "{\"ph\":\"M\",\"name\":\"process_name\",\"pid\":" << pid
        << ",\"tid\":0,\"args\":{\"name\":" << json_string(name) << "}}";
  }
  for (const auto& [thread, nodes] : thread_nodes) {
    std::string name;
    for (const auto& n : nodes) name += (name.empty() ? "" : ", ") + n;
    begin_event();
    out << "{\"ph\":\"M\",\"name\":\"thread_name\",\"pid\":" << thread.first
        << ",\"tid\":" << thread.second << ",\"args\":{\"name\":" << json_string(name) << "}}";
  }
  for (const TimelineEvent& e : a.timeline) {
    begin_event();
    switch (e.kind) {
      case TimelineEvent::Kind::kCallback:
        out << "{\"ph\":\"X\",\"cat\":\"callback\",\"name\":" << json_string(e.node + " " + e.what)
            << ",\"pid\":" << e.pid << ",\"tid\":" << e.tid << ",\"ts\":" << micros(e.ts - origin)
            << ",\"dur\":" << micros(e.duration) << ",\"args\":{\"node\":" << json_string(e.node)
            << ",\"source\":" << json_string(e.what) << "}}";
        break;
      case TimelineEvent::Kind::kPublish:
      case TimelineEvent::Kind::kTake: {
        const char* what = e.kind == TimelineEvent::Kind::kPublish ? "publish" : "take";
        out << "{\"ph\":\"i\",\"s\":\"t\",\"cat\":\"" << what
            << "\",\"name\":" << json_string(std::string(what) + " " + e.what)
            << ",\"pid\":" << e.pid << ",\"tid\":" << e.tid << ",\"ts\":" << micros(e.ts - origin)
            << ",\"args\":{\"node\":" << json_string(e.node) << ",\"topic\":" << json_string(e.what)
            << "}}";
        break;
      }
    }
  }
  if (a.path) {
    std::string name;
    for (const auto& t : a.path->topics) name += (name.empty() ? "" : " -> ") + t;
    const std::string quoted_name = json_string(name);
    uint64_t id = 0;
    for (const auto& instance : a.path->instances) {
      ++id;
      for (const bool start : {true, false}) {
        begin_event();
        out << "{\"ph\":\"" << (start ? 'b' : 'e') << "\",\"cat\":\"path\",\"name\":" << quoted_name
            << ",\"id\":" << id << ",\"pid\":" << instance.vpid << ",\"tid\":" << instance.vtid
            << ",\"ts\":" << micros((start ? instance.start : instance.end) - origin) << "}";
      }
    }
  }
  out << "\n]}\n";
}

}  // namespace robotperf::tracing
