#include "robotperf/files/paths.hpp"

#include <stdexcept>
#include <string>

namespace robotperf::files {

bool is_inside(const std::filesystem::path& folder, const std::filesystem::path& path) {
  const std::filesystem::path relative =
      path.lexically_normal().lexically_relative(folder.lexically_normal());
  return !relative.empty() && relative != "." && *relative.begin() != "..";
}

std::filesystem::path path_inside(const std::filesystem::path& folder, const std::string& name) {
  const std::filesystem::path path = folder / name;
  if (!is_inside(folder, path) || name.find('\n') != std::string::npos) {
    throw std::invalid_argument("the file name '" + name + "' would leave the output folder " +
                                folder.string());
  }
  return path;
}

}  // namespace robotperf::files
