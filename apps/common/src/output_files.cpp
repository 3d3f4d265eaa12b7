#include "rtog/app/output_files.hpp"

#include <fcntl.h>
#include <stdio.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <streambuf>

#include "temporaries.hpp"
#include "util/sink_buf.hpp"

namespace rtog::app {
namespace {

namespace fs = std::filesystem;

std::string quoted(const std::string& option, const std::string& path) { return option + " '" + path + "'"; }

std::runtime_error systemError(const std::string& what, int err) {
  return std::runtime_error("cannot write " + what + ": " + std::strerror(err));
}

/// Writes a stream buffer's bytes to a file descriptor, and throws, naming the file and the
/// system's reason (ENOSPC, EFBIG, EIO, ...), at the first failed write: with badbit in the
/// stream's exception mask the reason reaches the command through whatever writer was filling the
/// stream.
///
/// A stream output (a FIFO, a device) is opened at the first write or flush, from `open_path`:
/// opening a FIFO blocks until a reader comes, so every argument and input is checked first (a
/// bad option then fails at once, not after a reader came or never).
struct FdWriter {
  int& fd;
  std::string open_path, what, note;
  void operator()(const char* p, std::size_t n) {
    if (fd < 0) {
      fd = ::open(open_path.c_str(), O_WRONLY | O_NOCTTY | O_CLOEXEC);
      if (fd < 0) throw std::runtime_error("cannot write " + what + ": " + std::strerror(errno) + note);
    }
    while (n > 0) {
      const ssize_t w = ::write(fd, p, n);
      if (w < 0 && errno == EINTR) continue;
      if (w <= 0) throw std::runtime_error("cannot write " + what + ": " + std::strerror(w < 0 ? errno : EIO) + note);
      p += w;
      n -= static_cast<std::size_t>(w);
    }
  }
};
using FdBuf = detail::SinkBuf<FdWriter>;

/// What a path names once its symlinks are followed (a dangling link: the file it would
/// create). The kernel resolves the directories on the way by itself.
std::string followLinks(const std::string& what, const std::string& path) {
  std::string p = path;
  for (int hops = 0; hops < 40; ++hops) {
    struct stat st {};
    if (::lstat(p.c_str(), &st) != 0) {
      if (errno == ENOENT) return p;
      throw systemError(what, errno);
    }
    if (!S_ISLNK(st.st_mode)) return p;
    std::error_code ec;
    const fs::path target = fs::read_symlink(p, ec);
    if (ec) throw systemError(what, ec.value());
    p = target.is_absolute() ? target.string() : (fs::path(p).parent_path() / target).string();
  }
  throw systemError(what, ELOOP);
}

std::string directoryOf(const std::string& path) {
  const fs::path d = fs::path(path).parent_path();
  return d.empty() ? "." : d.string();
}

/// The process's umask, for the permissions a new file would get from open(2).
mode_t currentUmask() {
  const mode_t m = ::umask(0);
  ::umask(m);
  return m;
}

}  // namespace

struct OutputSet::Output {
  std::string option, path;
  std::string target;     ///< `path` with symlinks followed: what is written
  std::string tmp;        ///< temporary beside `target` (regular files); empty once gone
  bool special = false;   ///< device or FIFO: written through
  bool existed = false;   ///< the target existed when the command started
  bool swapped = false;   ///< exchanged with the old target, which now sits at `tmp`
  int fd = -1;
  dev_t dev = 0;          ///< identity: the file's device and inode, or (if it does not exist
  ino_t ino = 0;          ///< yet) its directory's and its name
  std::string name;
  std::unique_ptr<FdBuf> buf;
  std::unique_ptr<std::ostream> os;
};

OutputSet::OutputSet(std::vector<InputFile> inputs) : inputs_(std::move(inputs)) {}

OutputSet::~OutputSet() {
  for (auto& o : outputs_) {
    o->os.reset();
    // A FIFO never opened (the command failed first): a reader waiting on it is given its end of
    // file if there is one; none, and the open fails at once (ENXIO) instead of blocking.
    struct stat st {};
    if (o->special && o->fd < 0 && ::stat(o->path.c_str(), &st) == 0 && S_ISFIFO(st.st_mode))
      o->fd = ::open(o->path.c_str(), O_WRONLY | O_NOCTTY | O_CLOEXEC | O_NONBLOCK);
    if (o->fd >= 0) ::close(o->fd);
    if (!o->tmp.empty()) {
      ::unlink(o->tmp.c_str());
      temporaries::forget(o->tmp);
    }
  }
}

std::ostream& OutputSet::add(const std::string& option, const std::string& path) {
  if (path.empty()) throw std::invalid_argument(option + ": the path is empty (give a file name)");
  const std::string what = quoted(option, path);
  auto o = std::make_unique<Output>();
  o->option = option;
  o->path = path;
  // What the path names, as the kernel resolves it (this also follows /proc's magic links,
  // such as /dev/stdout on a pipe, which have no path to resolve by hand).
  struct stat st {};
  const bool exists = ::stat(path.c_str(), &st) == 0;
  if (!exists && errno != ENOENT) throw systemError(what, errno);
  o->target = path;
  int held = -1;  // this process's stdout or stderr, if the output is that file
  if (exists) {
    if (S_ISDIR(st.st_mode)) throw std::invalid_argument(what + " is a directory (give a file name)");
    if (S_ISSOCK(st.st_mode)) throw std::invalid_argument(what + " is a socket (give a file name)");
    o->special = S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode) || S_ISFIFO(st.st_mode);
    // `--ply /dev/stdout > file`: the shell holds the file open; replacing it would leave the
    // shell's (and the summary's) writes in an unlinked file. Written through that descriptor.
    for (const int fd : {STDOUT_FILENO, STDERR_FILENO}) {
      struct stat fst {};
      if (!o->special && held < 0 && ::fstat(fd, &fst) == 0 && fst.st_dev == st.st_dev && fst.st_ino == st.st_ino)
        held = fd;
    }
    o->special = o->special || held >= 0;
    if (!o->special) o->target = followLinks(what, path);  // the temporary goes beside the target
    o->dev = st.st_dev, o->ino = st.st_ino;
    o->existed = true;
  } else {
    o->target = followLinks(what, path);  // a dangling symlink: the file it names is created
    struct stat dir {};
    const std::string d = directoryOf(o->target);
    if (::stat(d.c_str(), &dir) != 0) throw systemError(what, errno);
    if (!S_ISDIR(dir.st_mode)) throw systemError(what, ENOTDIR);
    o->dev = dir.st_dev, o->ino = dir.st_ino;
    o->name = fs::path(o->target).filename().string();
  }
  for (const InputFile& in : inputs_) {
    struct stat is {};
    if (exists && ::stat(in.path.c_str(), &is) == 0 && is.st_dev == o->dev && is.st_ino == o->ino)
      throw std::invalid_argument(what + " is the input " + quoted(in.option, in.path) +
                                  " (the same file): refusing to overwrite an input");
  }
  for (const auto& other : outputs_)
    if (other->dev == o->dev && other->ino == o->ino && other->name == o->name)
      throw std::invalid_argument(what + " is named twice: it is the same file as " +
                                  quoted(other->option, other->path));

  std::string note;
  if (o->special) {
    // A stream (a terminal, /dev/null, a pipe, the caller's stdout): there is nothing to
    // replace, and writing beside it would replace the node itself.
    // The caller's own stdout or stderr now; any other node at the first write (FdBuf).
    if (held >= 0) {
      o->fd = ::fcntl(held, F_DUPFD_CLOEXEC, 0);
      if (o->fd < 0) throw systemError(what, errno);
    }
  } else {
    if (exists && ::access(o->target.c_str(), W_OK) != 0) throw systemError(what, errno);
    const std::string dir = directoryOf(o->target);
    // Hidden, and unique: a user's own FILE.partial (or any name) is never touched.
    std::string tmpl = dir + "/." + fs::path(o->target).filename().string() + ".rtog-XXXXXX";
    // Registered as it is created: SIGINT, SIGTERM or SIGHUP remove it (temporaries.hpp).
    o->fd = temporaries::create(tmpl, O_CLOEXEC);
    if (o->fd < 0)
      throw std::runtime_error("cannot write " + what + ": cannot create a temporary file in '" + dir +
                               "': " + std::strerror(errno));
    o->tmp = tmpl;
    // The permissions open(2) would have given: the old file's, else 0666 less the umask.
    ::fchmod(o->fd, exists ? (st.st_mode & 07777) : (0666 & ~currentUmask()));
    note = exists ? " (the old file is left as it was)" : "";
  }
  o->buf = std::make_unique<FdBuf>(FdWriter{o->fd, o->special ? path : std::string(), what, note});
  o->os = std::make_unique<std::ostream>(o->buf.get());
  o->os->exceptions(std::ios::badbit);
  outputs_.push_back(std::move(o));
  return *outputs_.back()->os;
}

void OutputSet::commit() {
  if (committed_) throw std::logic_error("OutputSet::commit: committed twice");
  // 1. Everything written and on the disk, before any target is touched.
  for (auto& o : outputs_) {
    o->os->flush();  // throws with the reason if a write fails
    if (!o->special && ::fsync(o->fd) != 0) throw systemError(quoted(o->option, o->path), errno);
    const int fd = o->fd;
    o->fd = -1;
    if (::close(fd) != 0) throw systemError(quoted(o->option, o->path), errno);
  }
  // 2. Into place. An existing target is exchanged with its temporary (atomically), so that it
  // can be put back if a later rename fails; a new one is renamed. Signals wait until the
  // renames are all done or all undone.
  const temporaries::HoldSignals hold;
  std::vector<Output*> done;
  try {
    for (auto& o : outputs_) {
      if (o->special) continue;
      if (::renameat2(AT_FDCWD, o->tmp.c_str(), AT_FDCWD, o->target.c_str(), RENAME_EXCHANGE) == 0) {
        o->swapped = true;
      } else if (::rename(o->tmp.c_str(), o->target.c_str()) != 0) {  // new target, or no exchange here
        throw std::runtime_error("cannot rename the temporary of " + quoted(o->option, o->path) + ": " +
                                 std::strerror(errno) + " (no output was replaced)");
      } else {
        temporaries::forget(o->tmp);
        o->tmp.clear();
      }
      done.push_back(o.get());
    }
  } catch (...) {
    for (auto it = done.rbegin(); it != done.rend(); ++it) {
      Output& o = **it;
      if (o.swapped) {
        ::renameat2(AT_FDCWD, o.tmp.c_str(), AT_FDCWD, o.target.c_str(), RENAME_EXCHANGE);
      } else if (!o.existed) {
        ::unlink(o.target.c_str());  // it did not exist before this command
      }  // (an old file replaced where the file system cannot exchange is gone: nothing to undo)
    }
    throw;
  }
  committed_ = true;
  // 3. The old contents, now under the temporary names, go; the renames are made durable.
  std::vector<std::string> dirs;
  for (auto& o : outputs_) {
    if (o->swapped) ::unlink(o->tmp.c_str());
    temporaries::forget(o->tmp);
    o->tmp.clear();
    if (o->special) continue;
    const std::string d = directoryOf(o->target);
    bool seen = false;
    for (const auto& x : dirs) seen = seen || x == d;
    if (!seen) dirs.push_back(d);
  }
  for (const auto& d : dirs) {
    const int fd = ::open(d.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) continue;
    ::fsync(fd);
    ::close(fd);
  }
}

}  // namespace rtog::app
