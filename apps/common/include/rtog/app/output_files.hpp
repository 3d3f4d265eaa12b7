// Every file an rtog tool (rtog, rtog-bench, rtog-accuracy) writes goes through one OutputSet, so
// that no tool can lose data in its own way:
// - an output that is one of the command's inputs, or another of its outputs, is refused
//   (device and inode compared, so `./x`, symlinks and hard links are caught);
// - a regular file is written to a unique temporary beside it (mkstemp: a user's `FILE.partial`
//   or anything else is never touched), fsync'ed, and only when every output of the command was
//   written completely are they all renamed into place (and the directories fsync'ed): all or
//   none. A full disk or a size limit therefore leaves the old file intact;
// - a symlink is followed to its target, which is written (the link stays a link);
// - a character or block device, a FIFO, or the file behind this process's stdout/stderr
//   (`--ply /dev/stdout > f`) is written through (a stream has nothing to replace);
//   a directory, a socket or an empty path is refused.
// Every error names the option and the path.
#pragma once

#include <memory>
#include <ostream>
#include <string>
#include <vector>

namespace rtog::app {

/// A file a command reads, named by the option that gave it (for messages).
struct InputFile {
  std::string option;  ///< e.g. "--rawlog", "map"
  std::string path;
};

class OutputSet {
 public:
  /// `inputs`: every file the command reads; outputs may be none of them.
  explicit OutputSet(std::vector<InputFile> inputs = {});
  ~OutputSet();  ///< an uncommitted set removes its temporaries; targets are untouched
  OutputSet(const OutputSet&) = delete;
  OutputSet& operator=(const OutputSet&) = delete;

  /// Checks and opens an output before anything is written (so a bad path fails at once, not
  /// after the work): throws std::invalid_argument for an empty path, a directory, a socket,
  /// an input or an output named twice, std::runtime_error if the temporary cannot be created.
  /// The stream stays valid until commit() or destruction.
  std::ostream& add(const std::string& option, const std::string& path);

  /// Flushes and checks every output, fsyncs, renames the temporaries into place and fsyncs
  /// their directories. Throws std::runtime_error naming the file if any write failed: then
  /// no target was replaced (and renames already done are undone).
  void commit();

 private:
  struct Output;
  std::vector<InputFile> inputs_;
  std::vector<std::unique_ptr<Output>> outputs_;
  bool committed_ = false;
};

}  // namespace rtog::app
