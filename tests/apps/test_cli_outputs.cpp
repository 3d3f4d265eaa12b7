// The files rtog writes, as a careless or hostile user would point them: at its inputs, at a
// directory next to a good output, at a user's own FILE.partial, through symlinks, at device
// nodes and FIFOs, onto a full disk. Nothing the user had may be lost (output_files.hpp).
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <sstream>

#include "cli_helpers.hpp"
#include "commands.hpp"
#include "rtog/core/mesh_export.hpp"

using namespace rtog_cli_test;

namespace {

const std::string kSena = std::string(RTOG_MRPT_DATASETS) + "/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog";

std::string plyOf(const std::string& map) {
  std::ostringstream os;
  rtog::writeOccupiedPly(rtog::cli::loadMap(map), os);
  return os.str();
}

void copyFile(const std::string& from, const std::string& to) { writeAll(to, readAll(from)); }

TEST(CliOutputs, NeverOverwriteAnInput) {
  const std::string d = scratch("same_file");
  const std::string log = d + "/in.rawlog", ini = d + "/map.ini", map = d + "/m.rtog";
  copyFile(kSena, log);
  copyFile(smallMap(), map);
  writeAll(ini, "[MappingApplication]\nrtreeOccupancyGrid_count=1\n");
  ASSERT_EQ(symlink("in.rawlog", (d + "/link.rtog").c_str()), 0);
  ASSERT_EQ(link(log.c_str(), (d + "/hard.rtog").c_str()), 0);
  ASSERT_EQ(symlink("m.rtog", (d + "/mlink.ply").c_str()), 0);
  ASSERT_EQ(link(map.c_str(), (d + "/mhard.bt").c_str()), 0);
  const std::string log_bytes = readAll(log), map_bytes = readAll(map), ini_bytes = readAll(ini);
  std::string out;
  // The same file by name, through "./", a symlink, a hard link; the rawlog and the .ini.
  for (const std::string& o : {log, d + "/./in.rawlog", d + "/link.rtog", d + "/hard.rtog"}) {
    EXPECT_EQ(run("build --rawlog " + log + " --resolution 0.2 --max-range 30 --out " + o, &out), 1) << o;
    EXPECT_NE(out.find("is the input --rawlog"), std::string::npos) << o << ": " << out;
  }
  EXPECT_EQ(run("build --rawlog " + log + " --ini " + ini + " --out " + ini, &out), 1);
  EXPECT_NE(out.find("is the input --ini"), std::string::npos) << out;
  for (const std::string& o : {"--ply " + d + "/./m.rtog", "--ply " + d + "/mlink.ply", "--bt " + d + "/mhard.bt",
                               "--png " + d + "/../" + d.substr(d.rfind('/') + 1) + "/m.rtog --slice-z 0.3"}) {
    EXPECT_EQ(run("export " + map + " " + o, &out), 1) << o;
    EXPECT_NE(out.find("is the input map"), std::string::npos) << o << ": " << out;
  }
  EXPECT_TRUE(readAll(log) == log_bytes) << "the rawlog was changed";
  EXPECT_TRUE(readAll(map) == map_bytes) << "the map was changed";
  EXPECT_TRUE(readAll(ini) == ini_bytes) << "the .ini was changed";
  EXPECT_TRUE(isSymlink(d + "/link.rtog") && isSymlink(d + "/mlink.ply"));
  // Two outputs that are one file.
  EXPECT_EQ(run("export " + map + " --ply " + d + "/x.ply --bt " + d + "/./x.ply", &out), 1);
  EXPECT_NE(out.find("named twice"), std::string::npos) << out;
  EXPECT_EQ(entries(d), (std::vector<std::string>{"hard.rtog", "in.rawlog", "link.rtog", "m.rtog", "map.ini",
                                                  "mhard.bt", "mlink.ply"}));
}

// A command with several outputs commits all or none: a bad one refuses the call before any
// output is touched.
TEST(CliOutputs, AllOrNothing) {
  const std::string d = scratch("all_or_nothing");
  const std::string keep = d + "/keep.ply", bt = d + "/keep.bt";
  ASSERT_EQ(mkdir((d + "/a_directory").c_str(), 0755), 0);
  writeAll(keep, "the user's old mesh");
  writeAll(bt, "the user's old tree");
  std::string out;
  EXPECT_EQ(run("export " + smallMap() + " --ply " + keep + " --bt " + d + "/a_directory", &out), 1);
  EXPECT_NE(out.find("--bt '" + d + "/a_directory' is a directory"), std::string::npos) << out;
  EXPECT_EQ(run("export " + smallMap() + " --ply " + keep + " --bt " + bt + " --png " + d +
                    "/no/such/dir/s.png --slice-z 0.3",
                &out),
            1);
  EXPECT_NE(out.find("--png '" + d + "/no/such/dir/s.png'"), std::string::npos) << out;
  // The slice height is checked after the outputs are opened: their temporaries go.
  EXPECT_EQ(run("export " + smallMap() + " --ply " + keep + " --png " + d + "/s.png --slice-z 99", &out), 1);
  EXPECT_NE(out.find("outside the map's height range"), std::string::npos) << out;
  EXPECT_TRUE(readAll(keep) == "the user's old mesh") << "keep was changed";
  EXPECT_TRUE(readAll(bt) == "the user's old tree") << "bt was changed";
  EXPECT_EQ(entries(d), (std::vector<std::string>{"a_directory", "keep.bt", "keep.ply"}));
  // And when all are good, all are written.
  ASSERT_EQ(run("export " + smallMap() + " --ply " + keep + " --bt " + bt, &out), 0) << out;
  EXPECT_TRUE(readAll(keep) == plyOf(smallMap()));
  EXPECT_EQ(readAll(bt).rfind("# Octomap OcTree binary file\n", 0), 0u);
  EXPECT_EQ(entries(d), (std::vector<std::string>{"a_directory", "keep.bt", "keep.ply"}));
}

TEST(CliOutputs, UniqueTemporariesLeaveTheUsersFilesAlone) {
  const std::string d = scratch("partial");
  writeAll(d + "/m.ply.partial", "the user's own file");
  writeAll(d + "/m.ply", "old");
  ASSERT_EQ(chmod((d + "/m.ply").c_str(), 0640), 0);
  std::string out;
  ASSERT_EQ(run("export " + smallMap() + " --ply " + d + "/m.ply", &out), 0) << out;
  EXPECT_TRUE(readAll(d + "/m.ply.partial") == "the user's own file") << "the user's m.ply.partial was changed";
  EXPECT_TRUE(readAll(d + "/m.ply") == plyOf(smallMap()));
  struct stat st {};
  ASSERT_EQ(stat((d + "/m.ply").c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0640u) << "a replaced file keeps its permissions";
  EXPECT_EQ(entries(d), (std::vector<std::string>{"m.ply", "m.ply.partial"}));
}

TEST(CliOutputs, SymlinksAreWrittenThroughNotReplaced) {
  const std::string d = scratch("symlink");
  ASSERT_EQ(mkdir((d + "/real").c_str(), 0755), 0);
  writeAll(d + "/real/target.ply", "old");
  ASSERT_EQ(symlink("real/target.ply", (d + "/link.ply").c_str()), 0);
  ASSERT_EQ(symlink("real/new.bt", (d + "/dangling.bt").c_str()), 0);
  std::string out;
  ASSERT_EQ(run("export " + smallMap() + " --ply " + d + "/link.ply --bt " + d + "/dangling.bt", &out), 0) << out;
  EXPECT_TRUE(isSymlink(d + "/link.ply"));
  EXPECT_TRUE(isSymlink(d + "/dangling.bt"));
  EXPECT_TRUE(readAll(d + "/real/target.ply") == plyOf(smallMap()));
  EXPECT_EQ(readAll(d + "/real/new.bt").rfind("# Octomap OcTree binary file\n", 0), 0u);
  EXPECT_EQ(entries(d), (std::vector<std::string>{"dangling.bt", "link.ply", "real"}));
  EXPECT_EQ(entries(d + "/real"), (std::vector<std::string>{"new.bt", "target.ply"}));
}

TEST(CliOutputs, FifosAreWrittenThrough) {
  const std::string d = scratch("fifo");
  ASSERT_EQ(mkfifo((d + "/pipe").c_str(), 0644), 0);
  // A reader that gives up after 20 s if nothing ever opens the FIFO for writing.
  ASSERT_EQ(std::system(("(timeout 20 cat '" + d + "/pipe' > '" + d + "/got'; touch '" + d + "/done') &").c_str()), 0);
  std::string out;
  EXPECT_EQ(run("export " + smallMap() + " --ply " + d + "/pipe", &out), 0) << out;
  for (int i = 0; i < 250 && access((d + "/done").c_str(), F_OK) != 0; ++i) usleep(100000);
  struct stat st {};
  ASSERT_EQ(lstat((d + "/pipe").c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode)) << "the FIFO was replaced";
  EXPECT_TRUE(readAll(d + "/got") == plyOf(smallMap()));
  EXPECT_EQ(entries(d), (std::vector<std::string>{"done", "got", "pipe"}));
}

// /dev/stdout on a pipe (a /proc magic link with no path behind it) and on a file the shell
// opened: written through the stream, the file not replaced under the shell. (Not to be run
// against the old scheme as root: it renamed its temporary over /dev/stdout itself.)
TEST(CliOutputs, StdoutIsWrittenThroughAsAStream) {
  const std::string d = scratch("stdout");
  const std::string ply = plyOf(smallMap());
  ASSERT_EQ(std::system((exe() + " export " + smallMap() + " --ply /dev/stdout | cat > '" + d + "/piped'").c_str()), 0);
  ASSERT_EQ(std::system((exe() + " export " + smallMap() + " --ply /dev/stdout > '" + d + "/file'").c_str()), 0);
  for (const std::string f : {"piped", "file"}) {
    const std::string got = readAll(d + "/" + f);
    EXPECT_TRUE(got.compare(0, ply.size(), ply) == 0) << f << ": not the mesh";
    EXPECT_EQ(got.substr(ply.size()), "wrote /dev/stdout: " + got.substr(ply.size() + 19)) << f;  // then the summary
  }
  EXPECT_EQ(entries(d), (std::vector<std::string>{"file", "piped"}));
}

// Device nodes are streams: written through, never replaced (as root the old scheme replaced
// /dev/full with a regular file). Made in a scratch directory when the tests run as root, so
// that the system's own nodes are never at stake.
TEST(CliOutputs, DeviceNodesAreWrittenThroughNeverReplaced) {
  const std::string d = scratch("devices");
  std::string null_dev = "/dev/null", full_dev = "/dev/full";
  if (geteuid() == 0) {
    null_dev = d + "/null", full_dev = d + "/full";
    ASSERT_EQ(mknod(null_dev.c_str(), S_IFCHR | 0666, makedev(1, 3)), 0);
    ASSERT_EQ(mknod(full_dev.c_str(), S_IFCHR | 0666, makedev(1, 7)), 0);
  }
  const auto isCharDevice = [](const std::string& p) {
    struct stat st {};
    return lstat(p.c_str(), &st) == 0 && S_ISCHR(st.st_mode);
  };
  std::string out;
  EXPECT_EQ(run("export " + smallMap() + " --ply " + null_dev, &out), 0) << out;
  EXPECT_EQ(run("export " + smallMap() + " --ply " + full_dev, &out), 1) << out;
  EXPECT_NE(out.find("cannot write --ply '" + full_dev + "': No space left on device"), std::string::npos) << out;
  EXPECT_EQ(run(std::string("build --tum ") + RTOG_TEST_TUM_DIR + " --resolution 0.2 --stride 16 --out " + full_dev, &out), 1);
  EXPECT_NE(out.find("No space left on device"), std::string::npos) << out;
  EXPECT_TRUE(isCharDevice(null_dev) && isCharDevice(full_dev)) << "a device node was replaced";
  if (geteuid() == 0) {
    EXPECT_EQ(entries(d), (std::vector<std::string>{"full", "null"}));
  }
}

// A full disk (here: a file size limit, writes past it failing with EFBIG) leaves the old file
// byte for byte, says why, and leaves no temporary behind.
TEST(CliOutputs, AFullDiskLeavesTheOldFileIntact) {
  const std::string d = scratch("full_disk");
  const std::string map = d + "/m.rtog", ply = d + "/m.ply";
  copyFile(smallMap(), map);
  writeAll(ply, "old mesh");
  const std::string map_bytes = readAll(map);
  ASSERT_GT(map_bytes.size(), 20000u);
  const long limit = 16384;  // bytes: less than either new file
  Child c = spawn({"build", "--tum", RTOG_TEST_TUM_DIR, "--resolution", "0.1", "--stride", "16", "--out", map}, limit);
  EXPECT_EQ(c.rc, 1) << c.output;
  EXPECT_NE(c.output.find("rtog: error: cannot write --out '" + map + "': File too large (the old file is left as it was)"),
            std::string::npos)
      << c.output;
  c = spawn({"export", map, "--ply", ply, "--bt", d + "/new.bt"}, limit);
  EXPECT_EQ(c.rc, 1) << c.output;
  EXPECT_NE(c.output.find("File too large"), std::string::npos) << c.output;
  EXPECT_TRUE(readAll(map) == map_bytes) << "the old map was changed";
  EXPECT_TRUE(readAll(ply) == "old mesh") << "ply was changed";
  EXPECT_EQ(entries(d), (std::vector<std::string>{"m.ply", "m.rtog"}));
}

TEST(CliOutputs, EmptyPathsAreRefused) {
  const std::string d = scratch("empty");
  std::string out;
  EXPECT_EQ(run(std::string("build --tum ") + RTOG_TEST_TUM_DIR + " --resolution 0.2 --stride 16 --out ''", &out), 2);
  EXPECT_NE(out.find("--out: the path is empty"), std::string::npos) << out;
  // Next to a good output, which must not be written either.
  for (const auto& [o, other] : std::vector<std::pair<std::string, std::string>>{
           {"--ply", "--bt"}, {"--bt", "--ply"}, {"--scene", "--ply"}, {"--png", "--bt"}}) {
    EXPECT_EQ(run("export " + smallMap() + " " + o + " '' " + other + " " + d + "/x" + (o == "--png" ? " --slice-z 0.3" : ""),
                  &out),
              2)
        << o;
    EXPECT_NE(out.find(o + ": the path is empty"), std::string::npos) << o << ": " << out;
  }
  EXPECT_EQ(run("info ''", &out), 2);
  EXPECT_NE(out.find("the path is empty"), std::string::npos) << out;
  EXPECT_TRUE(entries(d).empty());
}

}  // namespace

namespace {

// A FIFO with no reader as an output, and a request that fails on an argument or an input checked
// only once the map is read: the tool exits at once with the error (before: it blocked opening the
// FIFO for writing, waiting for a reader, before looking at anything else). The FIFO stays, and
// nothing else is written. The tool must finish within 60 s.
TEST(CliOutputs, AFifoWithNoReaderDoesNotHoldUpABadRequest) {
  const std::string d = scratch("fifo_no_reader");
  ASSERT_EQ(mkfifo((d + "/pipe").c_str(), 0644), 0);
  std::string out;
  for (const auto& [args, error] : std::vector<std::pair<std::string, std::string>>{
           {"export " + smallMap() + " --ply " + d + "/pipe --png " + d + "/s.png --slice-z 99",
            "--slice-z 99 m is outside the map's height range"},
           {"export " + d + "/missing.rtog --ply " + d + "/pipe", "cannot open map file"},
           {"image " + d + "/missing.rtog --out " + d + "/pipe", "cannot open map file"}}) {
    EXPECT_EQ(run(args, &out, "timeout 60 "), 1) << args << "\n" << out;
    EXPECT_NE(out.find(error), std::string::npos) << args << "\n" << out;
    struct stat st {};
    ASSERT_EQ(lstat((d + "/pipe").c_str(), &st), 0);
    EXPECT_TRUE(S_ISFIFO(st.st_mode)) << "the FIFO was replaced";
    EXPECT_EQ(entries(d), std::vector<std::string>{"pipe"}) << args;
  }
}

}  // namespace

namespace {

// Interrupted (SIGINT, SIGTERM, SIGHUP) while it builds, the tool removes its hidden temporary
// (.m.rtog.rtog-XXXXXX) and dies of the signal, as the caller expects (before: the temporary was
// left behind at every interruption).
TEST(CliOutputs, AnInterruptedRunLeavesNoTemporary) {
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) {
    SCOPED_TRACE(strsignal(sig));
    const std::string d = scratch("interrupted");
    std::cout.flush();
    std::fflush(nullptr);
    const pid_t pid = fork();
    if (pid == 0) {
      if (!freopen("/dev/null", "w", stdout)) _exit(126);
      const std::string e = exe(), out = d + "/m.rtog";
      // SENA at 1 cm: tens of seconds of work, interrupted within the first.
      execl(e.c_str(), e.c_str(), "build", "--rawlog", kSena.c_str(), "--resolution", "0.01", "--out", out.c_str(),
            static_cast<char*>(nullptr));
      _exit(127);
    }
    ASSERT_GT(pid, 0);
    // Once the temporary exists, the run is under way.
    bool started = false;
    for (int i = 0; i < 600 && !started; ++i) {
      for (const auto& name : entries(d)) started = started || name.rfind(".m.rtog.rtog-", 0) == 0;
      if (!started) usleep(50000);
    }
    EXPECT_TRUE(started) << "no temporary appeared";
    usleep(200000);
    kill(pid, sig);
    int status = 0;
    ASSERT_EQ(waitpid(pid, &status, 0), pid);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << "status " << status;
    EXPECT_EQ(entries(d), std::vector<std::string>{}) << "left behind";
  }
}

}  // namespace
