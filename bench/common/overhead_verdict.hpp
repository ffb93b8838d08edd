// The verdict of a bench that compares a time in the graph with its like-for-like reference:
// the overhead at p50, how far apart the two p50s may be by chance, and whether the graph came out
// faster than its reference beyond that (a bench defect: the reference does different or colder
// work, and the overhead figure says nothing).
#pragma once

#include <functional>
#include <string>
#include <vector>

namespace robotperf::bench {

struct OverheadVerdict {
  double reference_p50 = 0, graph_p50 = 0;  // over every round's samples
  double ratio = 0;                         // (graph - reference) / reference
  // How far apart the two p50s may be by chance, relative to the reference: the wider half of
  // the two medians' 95 % intervals, or half the spread of the rounds' own ratios where that is
  // wider (samples of one round are not independent: a kernel whose threads the scheduler places
  // well or badly for a while moves a whole round).
  double band = 0;
  double round_low = 0, round_high = 0;  // the rounds' own ratios
  // The same ratio at p10: the floor both sides reach when the scheduler places their threads
  // well. A kernel with threads of its own (OpenCV's) runs in two modes, and a round can catch
  // one side more often in the slow one; a reference doing different or colder work moves its
  // floor too.
  double floor_ratio = 0;
  // Faster than the reference beyond the band at p50 and at the floor, and in every round.
  bool defect = false;
  // Judged against the target with the band: met when the whole band is at or below it, not met
  // when the whole band is above it, undecided when the band holds it (or has no end).
  bool met = false;
  bool undecided = false;
};

// One round: the reference's and the graph's samples, taken in turns.
struct OverheadRound {
  std::vector<double> reference, graph;
};

OverheadVerdict judge_overhead(const std::vector<OverheadRound>& rounds, double target_ratio);

// "(met)", "(NOT met)", "(undecided)", "(information)" or "(BENCH DEFECT: ...)".
std::string verdict_text(const OverheadVerdict& v, bool target_applies);

// Benches registered as CTest smoke tests take --smoke (fewer samples) and exit 1 when a
// comparison came out as a bench defect, confirmed by confirm_defect(). --confirm marks the run
// of a bench that confirms another's defect.
struct BenchOptions {
  bool smoke = false;
  bool confirming = false;        // --confirm
  std::vector<std::string> args;  // the others: the benchmark ids
};
BenchOptions parse_bench_options(int argc, char** argv);

// A defect that one process shows can be that process's luck rather than the bench's fault: where
// the scheduler keeps its threads (one vCPU of a shared VM slower than the other for a while) and
// where its buffers landed hold for the whole process, so its rounds are not independent draws of
// them. A reference that does different or colder work is slower in every process. Runs
// `command` (the bench again, with --confirm) in up to `processes` fresh processes, one after the
// other, and returns whether each found a defect too (exit status 1; 0: none). Throws
// std::runtime_error when one fails otherwise.
bool confirm_defect(const std::vector<std::string>& command, int processes = 2);

// The command that runs this bench again as a confirming process for one benchmark:
// /proc/self/exe, the same options (--smoke), `id` alone, and --confirm.
std::vector<std::string> confirming_command(const BenchOptions& options, const std::string& id);

// Each of `suspected` (benchmark ids whose comparison came out as a defect) confirmed on its own
// (confirm_defect of its confirming_command): a defect that fresh processes find in another
// benchmark confirms none. Returns whether any was confirmed.
bool confirm_defects(const BenchOptions& options, const std::vector<std::string>& suspected);

// The body of an overhead bench's main: `compare` for each of `ids` (it returns whether that
// benchmark's comparison came out as a defect), the suspected ones confirmed by confirm_defects
// unless this process is itself confirming one, then `after` (when given). Returns the bench's
// exit status: 0, 1 for a defect confirmed (or found by a confirming process), 2 for an error,
// printed to stderr as "<bench>: <what>".
int run_overhead_bench(const BenchOptions& options, const std::string& bench,
                       const std::vector<std::string>& ids,
                       const std::function<bool(const std::string&)>& compare,
                       const std::function<void()>& after = {});

// The columns of the kernel benches' comparison rows, and one row: the kernel's `label`, both
// p50s in ms, the overhead, its noise band and the verdict against `target_ratio`.
void print_overhead_columns();
void print_overhead_row(const std::string& label, const OverheadVerdict& v, double target_ratio);

}  // namespace robotperf::bench
