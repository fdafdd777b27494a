// Fuzz target: the run-log reader (server/sim/log/run_log_reader.cpp) and
// replay's index over it (ReplayTrack), as --replay reads a log. The input is
// the whole file. The reader may refuse a file with std::invalid_argument
// (not a log, corruption in the middle, frame ids out of order); anything
// else it throws, or a crash, is a finding. The file lives in a memfd opened
// by path, because the reader maps a path: one per process, overwritten and
// then cut to the input's length (cutting it to 0 first would free and
// fault in its pages again for every input).
#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "server/sim/log/replay_track.h"
#include "server/sim/log/run_log_reader.h"

namespace {

const std::string& LogPath() {
  static const std::string path = [] {
    const int fd = memfd_create("fuzz-runlog", 0);
    if (fd < 0) std::abort();
    return "/proc/self/fd/" + std::to_string(fd);
  }();
  return path;
}

void WriteInput(const uint8_t* data, std::size_t size) {
  const int fd = std::stoi(LogPath().substr(LogPath().rfind('/') + 1));
  std::size_t at = 0;
  while (at < size) {
    const ssize_t wrote = pwrite(fd, data + at, size - at, static_cast<off_t>(at));
    if (wrote <= 0) std::abort();
    at += static_cast<std::size_t>(wrote);
  }
  if (ftruncate(fd, static_cast<off_t>(size)) != 0) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  WriteInput(data, size);
  try {
    sim4cv::runlog::RunLogReader reader(LogPath());
    const sim4cv::runlog::ReplayTrack track(reader);
    // What replay and the tools ask of it.
    for (std::size_t i = 0; i < track.frame_count(); ++i) {
      for (const auto& entity : track.EntitiesAt(i)) {
        if (track.Find(track.frame_id(i), entity.id) == nullptr) __builtin_trap();
      }
    }
    if (!track.empty()) (void)track.PositionsOf(1);
  } catch (const std::invalid_argument&) {
    // refused, naming the file and the offset
  }
  return 0;
}
