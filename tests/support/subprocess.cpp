#include "subprocess.h"

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace whiskeye::testing {

Subprocess::Subprocess(const std::vector<std::string>& argv, std::string output_path,
                       const std::vector<std::string>& extra_env)
    : output_path_(std::move(output_path)) {
  if (argv.empty()) throw std::invalid_argument("Subprocess: empty argv");
  if (output_path_.empty()) {
    char tmpl[] = "/tmp/whiskeye-subprocess-XXXXXX";
    const int fd = ::mkstemp(tmpl);
    if (fd < 0) throw std::runtime_error("mkstemp failed");
    ::close(fd);
    output_path_ = tmpl;
    owns_output_ = true;
  }
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  std::vector<std::string> env_strings;
  for (char** e = environ; *e != nullptr; ++e) env_strings.emplace_back(*e);
  for (const auto& e : extra_env) env_strings.push_back(e);
  std::vector<char*> env;
  for (auto& e : env_strings) env.push_back(e.data());
  env.push_back(nullptr);

  const pid_t parent = ::getpid();
  pid_ = ::fork();
  if (pid_ < 0) throw std::runtime_error(std::string("fork failed: ") + std::strerror(errno));
  if (pid_ == 0) {
    // Killed with the test: a test process that ctest kills on its timeout (or that aborts) runs no
    // destructor, and a daemon left running would hold its ports and CPU through the rest of the
    // suite. (The signal follows the forking thread: Subprocesses are made on the test's main thread.)
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) std::_Exit(127);  // the test died before the line above
    const int fd = ::open(output_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      ::dup2(fd, 1);
      ::dup2(fd, 2);
      ::close(fd);
    }
    const int devnull = ::open("/dev/null", O_RDONLY);
    if (devnull >= 0) ::dup2(devnull, 0);
    // Nothing else of the test's: an inherited socket (the test's own LCM) would be counted as the
    // child's (slamd's receive drops are read per socket from /proc/net/udp) and outlive the test.
    ::close_range(3, ~0U, 0);
    ::setpgid(0, 0);  // its own process group, so stop() reaches grandchildren (xvfb-run, java)
    ::execvpe(args[0], args.data(), env.data());
    std::fprintf(stderr, "exec %s failed: %s\n", args[0], std::strerror(errno));
    std::_Exit(127);
  }
  ::setpgid(pid_, pid_);
}

Subprocess::~Subprocess() {
  if (!reaped_ && pid_ > 0) {
    ::kill(-pid_, SIGKILL);
    ::waitpid(pid_, nullptr, 0);
  }
  if (owns_output_) ::unlink(output_path_.c_str());
}

int Subprocess::wait(double timeout_s) {
  if (reaped_) return status_;
  const bool done = wait_until(
      [&] {
        int st = 0;
        const pid_t r = ::waitpid(pid_, &st, WNOHANG);
        if (r == pid_) {
          reaped_ = true;
          status_ = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
          return true;
        }
        return false;
      },
      timeout_s);
  return done ? status_ : -1;
}

bool Subprocess::running() { return wait(0.0) == -1; }

void Subprocess::signal(int sig) {
  if (!reaped_) ::kill(-pid_, sig);
}

int Subprocess::stop(double timeout_s, int sig) {
  signal(sig);
  int rc = wait(timeout_s);
  if (rc == -1) {
    signal(SIGKILL);
    rc = wait(5.0);
  }
  return rc;
}

std::string Subprocess::output() const {
  std::ifstream in(output_path_);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

int64_t proc_status_kb(int pid, const std::string& field) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(field + ":", 0) == 0) return std::stoll(line.substr(field.size() + 1));
  }
  return -1;
}

}  // namespace whiskeye::testing
