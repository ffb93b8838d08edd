// `robotperf bag info|echo|convert|reindex`: rosbag2 bags (bag_commands.cpp does the work).
#include "../bag_commands.hpp"
#include "commands.hpp"

namespace robotperf::cli {

namespace {

class BagCommand : public Command {
 public:
  CLI::App* declare(CLI::App& app) override {
    auto* command = app.add_subcommand("bag", "inspect, print and convert rosbag2 bags");
    command->require_subcommand(1);
    command->footer(
        "Examples: robotperf bag info my_bag --verify\n"
        "          robotperf bag convert my_bag my_bag_mcap --storage mcap");
    info_ = command->add_subcommand("info", "storage, duration, topics, counts, QoS");
    info_->add_option("bag", path_, "bag directory, .db3 or .mcap file")->required();
    info_->add_flag(
        "--verify", verify_,
        "also read every message and report, one line each, where the storage "
        "disagrees with metadata.yaml (counts, start, end, unreadable storage): exit 2");
    info_->footer("Example: robotperf bag info camera_bag --verify");
    declare_echo(*command);
    declare_convert(*command);
    reindex_ = command->add_subcommand(
        "reindex", "write metadata.yaml for a bag directory that lost it, from its storage files");
    reindex_->add_option("dir", reindex_dir_, "bag directory with .db3 or .mcap files")->required();
    reindex_->footer("Example: robotperf bag reindex camera_bag");
    return command;
  }

  int run(const Context&) override {
    if (*info_) return bag_info(path_, verify_);
    if (*echo_) return bag_echo(path_, echo_options_);
    if (*convert_) return bag_convert(path_, convert_out_, convert_options_);
    return bag_reindex(reindex_dir_);
  }

 private:
  void declare_echo(CLI::App& bag) {
    echo_ = bag.add_subcommand("echo", "print messages as YAML");
    echo_->add_option("bag", path_, "bag directory, .db3 or .mcap file")->required();
    echo_->add_option("--topic", echo_options_.topics, "only this topic (repeatable)");
    echo_->add_option("--limit", echo_options_.limit, "print at most N messages")
        ->transform(whole_number(0));
    echo_->add_option("--msg-dir", echo_options_.msg_dirs,
                      "folder of .msg files (<pkg>/msg/*.msg, or flat) for types the bag "
                      "has no definition of");
    echo_
        ->add_option("--max-array", echo_options_.max_array,
                     "summarise arrays longer than this (default 64)")
        ->transform(whole_number(0));
    echo_->footer("Example: robotperf bag echo camera_bag --topic /image --limit 3");
  }

  void declare_convert(CLI::App& bag) {
    ConvertOptions& o = convert_options_;
    convert_ = bag.add_subcommand("convert", "write a bag in another storage");
    convert_->add_option("in", path_, "bag directory, .db3 or .mcap file")->required();
    convert_->add_option("out", convert_out_, "new bag directory")->required();
    convert_->add_option("--storage", o.storage, "sqlite3 or mcap (default mcap)")
        ->check(CLI::IsMember({"sqlite3", "mcap"}));
    convert_->add_option("--compression", o.compression, "MCAP chunks: zstd, lz4 or none")
        ->check(CLI::IsMember({"zstd", "lz4", "none"}));
    convert_->add_option("--chunk-size", o.chunk_size, "MCAP chunk size in bytes")
        ->transform(whole_number(0));
    convert_->add_option("--max-file-size", o.max_file_mib,
                         "split into files of about this many MiB (0 = one file)");
    convert_->add_option(
        "--msg-dir", o.msg_dirs,
        "folder of .msg files giving the definitions the bag lacks, written into the new bag");
    convert_->footer("Example: robotperf bag convert camera_bag camera_mcap --storage mcap");
  }

  std::string path_;
  bool verify_ = false;
  EchoOptions echo_options_;
  ConvertOptions convert_options_;
  std::string convert_out_;
  std::string reindex_dir_;
  CLI::App* info_ = nullptr;
  CLI::App* echo_ = nullptr;
  CLI::App* convert_ = nullptr;
  CLI::App* reindex_ = nullptr;
};

}  // namespace

std::unique_ptr<Command> bag_command() {
  return std::make_unique<BagCommand>();
}

}  // namespace robotperf::cli
