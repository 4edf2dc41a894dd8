#pragma once
// Harness of the command-line tests (cli_test.cpp, cli_frf_test.cpp): runs
// the fdsid executable (FDSID_EXE) as a child process with a time limit and
// checks the contracts' exit status and one-line stderr.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cerrno>
#include <initializer_list>
#include <sstream>
#include <string>
#include <vector>

namespace fdsid::cli_harness {

inline const std::string kExe = FDSID_EXE;

// ---------------------------------------------------------------------------
// Running fdsid

struct RunResult {
  int status = -1;         ///< exit status, or 128 + signal when killed
  bool timed_out = false;  ///< killed after the time limit
  std::string out, err;    ///< everything written to stdout / stderr
  std::string command;     ///< the command line, for failure messages
};

/// Runs exe with args (stdin from /dev/null), captures stdout and stderr, and
/// kills it after timeout_s seconds so that a hang fails the test instead of
/// blocking ctest.
inline RunResult run_command(const std::string& exe, const std::vector<std::string>& args, int timeout_s) {
  RunResult res;
  res.command = exe;
  for (const auto& a : args) res.command += " " + a;

  int out_pipe[2], err_pipe[2];
  if (pipe(out_pipe) != 0 || pipe(err_pipe) != 0) {
    res.err = "pipe() failed";
    return res;
  }
  const pid_t pid = fork();
  if (pid < 0) {
    res.err = "fork() failed";
    return res;
  }
  if (pid == 0) {
    const int devnull = open("/dev/null", O_RDONLY);
    if (devnull >= 0) dup2(devnull, STDIN_FILENO);
    dup2(out_pipe[1], STDOUT_FILENO);
    dup2(err_pipe[1], STDERR_FILENO);
    close(out_pipe[0]);
    close(out_pipe[1]);
    close(err_pipe[0]);
    close(err_pipe[1]);
    std::vector<char*> argv;
    argv.push_back(const_cast<char*>(exe.c_str()));
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(exe.c_str(), argv.data());
    _exit(127);
  }
  close(out_pipe[1]);
  close(err_pipe[1]);

  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(timeout_s);
  pollfd fds[2] = {{out_pipe[0], POLLIN, 0}, {err_pipe[0], POLLIN, 0}};
  std::string* sinks[2] = {&res.out, &res.err};
  int open_fds = 2;
  char buf[4096];
  while (open_fds > 0) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      res.timed_out = true;
      kill(pid, SIGKILL);
      break;
    }
    const int ready = poll(fds, 2, static_cast<int>(std::min<long long>(left.count(), 1000)));
    if (ready < 0 && errno != EINTR) break;
    for (int i = 0; i < 2; ++i) {
      if (fds[i].fd < 0 || !(fds[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      const ssize_t n = read(fds[i].fd, buf, sizeof buf);
      if (n > 0) {
        sinks[i]->append(buf, static_cast<size_t>(n));
      } else if (n == 0 || errno != EINTR) {
        close(fds[i].fd);
        fds[i].fd = -1;
        --open_fds;
      }
    }
  }
  for (auto& f : fds)
    if (f.fd >= 0) close(f.fd);
  int wstatus = 0;
  while (waitpid(pid, &wstatus, 0) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(wstatus)) res.status = WEXITSTATUS(wstatus);
  else if (WIFSIGNALED(wstatus)) res.status = 128 + WTERMSIG(wstatus);
  return res;
}

/// The default hang guard of one fdsid run: 600 s. A guard, not a timing test
/// (timings live in bench/): it must sit well above the slowest legitimate run
/// in the slowest build. Under ASan + UBSan + coverage at -O1 the 50-digit
/// oracle of `check` on M = 64 and `gap-validate` on 20 cases take 100-150 s
/// on 2 busy cores (Release: 1-5 s), so 120 s tripped on correct runs.
constexpr int kHangGuardSeconds = 600;

inline RunResult run_fdsid(const std::vector<std::string>& args, int timeout_s = kHangGuardSeconds) {
  return run_command(kExe, args, timeout_s);
}

/// Runs fdsid on a pseudo-terminal through util-linux `script` (stdout and
/// stderr both arrive in `out`), for what fdsid prints on a terminal only.
inline RunResult run_fdsid_via_script(const std::vector<std::string>& args, int timeout_s = kHangGuardSeconds) {
  std::string line = kExe;
  for (const auto& a : args) line += " '" + a + "'";
  return run_command("/usr/bin/script", {"-qec", line, "/dev/null"}, timeout_s);
}

inline std::string describe(const RunResult& r) {
  std::ostringstream s;
  s << "command: " << r.command << "\nexit status: " << r.status << (r.timed_out ? " (killed: timed out)" : "")
    << "\nstderr: [" << r.err << "]\nstdout (first 500 chars): [" << r.out.substr(0, 500) << "]";
  return s.str();
}

/// Exit status 2 and exactly one line "fdsid: ..." on stderr containing every
/// one of the given substrings.
inline ::testing::AssertionResult IsBadInput(const RunResult& r, std::initializer_list<std::string> needles) {
  if (r.timed_out) return ::testing::AssertionFailure() << "timed out\n" << describe(r);
  if (r.status != 2) return ::testing::AssertionFailure() << "expected exit status 2\n" << describe(r);
  if (r.err.empty() || r.err.back() != '\n' || std::count(r.err.begin(), r.err.end(), '\n') != 1)
    return ::testing::AssertionFailure() << "stderr is not exactly one line\n" << describe(r);
  if (r.err.rfind("fdsid: ", 0) != 0)
    return ::testing::AssertionFailure() << "stderr does not start with \"fdsid: \"\n" << describe(r);
  for (const auto& n : needles)
    if (r.err.find(n) == std::string::npos)
      return ::testing::AssertionFailure() << "stderr does not mention \"" << n << "\"\n" << describe(r);
  return ::testing::AssertionSuccess();
}

inline ::testing::AssertionResult Succeeded(const RunResult& r) {
  if (r.timed_out || r.status != 0) return ::testing::AssertionFailure() << "expected exit status 0\n" << describe(r);
  return ::testing::AssertionSuccess();
}

}  // namespace fdsid::cli_harness
