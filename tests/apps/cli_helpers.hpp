// Running the real rtog binary as a process, and the files around it, for the CLI tests.
// RTOG_TEST_EXE (environment) runs the tests against another build of the tool, e.g. the code
// before a fix, to see a test fail there.
#pragma once

#include <dirent.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace rtog_cli_test {

/// What the tests of this process made under TempDir(), removed when the process ends.
struct Leftovers {
  std::vector<std::string> paths;
  ~Leftovers() {
    for (const auto& p : paths) std::system(("rm -rf '" + p + "'").c_str());
  }
};
inline Leftovers& leftovers() {
  static Leftovers l;
  return l;
}

inline std::string exe() {
  const char* e = std::getenv("RTOG_TEST_EXE");
  return e && *e ? e : RTOG_EXE;
}

inline std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline void writeAll(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

/// `rtog <args>` through the shell (args may hold redirections and pipes: "... < x", "cat x |"
/// must then be written by the caller around exe()); stdout and stderr into *output.
inline int run(const std::string& args, std::string* output = nullptr, const std::string& prefix = "") {
  // Per process: ctest runs the cases in parallel processes.
  const std::string out_file = ::testing::TempDir() + "/rtog_cli_run_" + std::to_string(getpid()) + ".txt";
  static const bool once = (leftovers().paths.push_back(out_file), true);
  (void)once;
  const int rc = std::system((prefix + exe() + " " + args + " > " + out_file + " 2>&1").c_str());
  if (output) *output = readAll(out_file);
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : 128 + WTERMSIG(rc);
}

/// What one run of the tool did: exit code, output, peak memory.
struct Child {
  int rc = -1;
  std::string output;
  long maxrss_kb = 0;
};

/// Runs the tool directly (no shell), optionally with RLIMIT_FSIZE (SIGXFSZ ignored, so that a
/// write past the limit fails with EFBIG as on a full disk instead of killing the process).
inline Child spawn(const std::vector<std::string>& args, long file_size_limit = -1) {
  const std::string out_file = ::testing::TempDir() + "/rtog_cli_spawn_" + std::to_string(getpid()) + ".txt";
  static const bool once = (leftovers().paths.push_back(out_file), true);
  (void)once;
  Child c;
  std::cout.flush();  // else the child inherits (and writes) what this process had buffered
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid == 0) {
    if (file_size_limit >= 0) {
      signal(SIGXFSZ, SIG_IGN);
      const rlimit lim{static_cast<rlim_t>(file_size_limit), static_cast<rlim_t>(file_size_limit)};
      setrlimit(RLIMIT_FSIZE, &lim);
    }
    if (!freopen(out_file.c_str(), "w", stdout) || dup2(fileno(stdout), 2) < 0) _exit(126);
    std::vector<char*> argv;
    const std::string e = exe();
    argv.push_back(const_cast<char*>(e.c_str()));
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  int status = 0;
  rusage ru{};
  wait4(pid, &status, 0, &ru);
  c.rc = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  c.maxrss_kb = ru.ru_maxrss;
  c.output = readAll(out_file);
  return c;
}

/// A fresh, empty directory of this process.
inline std::string scratch(const std::string& name) {
  const std::string d = ::testing::TempDir() + "/rtog_" + name + "_" + std::to_string(getpid());
  EXPECT_EQ(std::system(("rm -rf '" + d + "' && mkdir -p '" + d + "'").c_str()), 0);
  leftovers().paths.push_back(d);
  return d;
}

/// The names in a directory, sorted (to see that nothing else was left behind).
inline std::vector<std::string> entries(const std::string& dir) {
  std::vector<std::string> out;
  if (DIR* d = opendir(dir.c_str())) {
    while (const dirent* e = readdir(d))
      if (std::string(e->d_name) != "." && std::string(e->d_name) != "..") out.push_back(e->d_name);
    closedir(d);
  }
  std::sort(out.begin(), out.end());
  return out;
}

inline bool isSymlink(const std::string& p) {
  struct stat st {};
  return lstat(p.c_str(), &st) == 0 && S_ISLNK(st.st_mode);
}

/// A small map built by the tool from the bundled frames (once per process).
inline const std::string& smallMap() {
  static const std::string path = [] {
    const std::string p = ::testing::TempDir() + "/rtog_cli_small_" + std::to_string(getpid()) + ".rtog";
    leftovers().paths.push_back(p);
    std::string out;
    EXPECT_EQ(run(std::string("build --tum ") + RTOG_TEST_TUM_DIR + " --resolution 0.2 --stride 16 --out " + p, &out), 0)
        << out;
    return p;
  }();
  return path;
}

}  // namespace rtog_cli_test
