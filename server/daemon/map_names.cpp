#include "server/daemon/map_names.h"

#include <algorithm>
#include <filesystem>
#include <system_error>
#include <vector>

#include "server/common/limits.h"

namespace sim4cv::daemon {

void ListMapNames(const std::string& maps_dir, google::protobuf::RepeatedPtrField<std::string>& names) {
  namespace fs = std::filesystem;
  // The walk is bounded too: a --maps-dir pointed at a huge tree costs the
  // sim thread (every client's frames wait) at most this many entries.
  constexpr std::size_t kMaxEntriesWalked = 20 * limits::kMaxListedMaps;
  std::vector<std::string> found;
  std::error_code error;
  const fs::path root(maps_dir);
  fs::recursive_directory_iterator it(root, fs::directory_options::skip_permission_denied, error);
  std::size_t walked = 0;
  for (; !error && it != fs::recursive_directory_iterator() && walked < kMaxEntriesWalked; it.increment(error)) {
    ++walked;
    const fs::directory_entry& entry = *it;
    std::error_code status_error;
    if (entry.path().extension() != ".map" || !entry.is_regular_file(status_error) || entry.is_symlink(status_error)) {
      continue;
    }
    fs::path relative = entry.path().lexically_relative(root);
    relative.replace_extension();
    found.push_back(relative.generic_string());
  }
  std::sort(found.begin(), found.end());
  if (found.size() > limits::kMaxListedMaps) found.resize(limits::kMaxListedMaps);
  for (std::string& name : found) names.Add(std::move(name));
}

}  // namespace sim4cv::daemon
