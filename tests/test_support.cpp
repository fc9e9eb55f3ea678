#include "test_support.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <poll.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>

namespace rgbdmap::test {

std::string dataDir() { return RGBDMAP_DATA_DIR; }
std::string tumDir(const std::string& name) { return dataDir() + "/tum/" + name; }
std::string binary() { return RGBDMAP_BINARY; }

namespace {

// `dir`, emptied (made if missing).
std::string emptied(const std::string& dir) {
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

std::string freshDirOf(const ::testing::TestInfo& info) {
  return std::string(RGBDMAP_TEST_TMP) + "/" + info.test_suite_name() + "." + info.name();
}

// A passing test's folder goes when it ends: the suite writes gigabytes of maps, sessions and
// sequences, three builds' worth on CI's disk. A failing test's stays for whoever looks into it,
// and RGBDMAP_TEST_KEEP_DIRS=1 keeps them all.
class RemoveFreshDirOfPassingTest : public ::testing::EmptyTestEventListener {
  void OnTestEnd(const ::testing::TestInfo& info) override {
    if (!info.result()->Passed()) return;
    std::error_code ignored;  // a folder a child process still writes in is left, not fatal
    std::filesystem::remove_all(freshDirOf(info), ignored);
  }
};

bool keepDirs() {
  const char* keep = std::getenv("RGBDMAP_TEST_KEEP_DIRS");
  return keep && std::string(keep) == "1";
}

void removeFreshDirsOfPassingTests() {
  if (keepDirs()) return;
  // gtest owns the listener once appended.
  ::testing::UnitTest::GetInstance()->listeners().Append(new RemoveFreshDirOfPassingTest);
}

// The folders of processDir(), removed when the process exits with every test passed.
struct ProcessDirs {
  std::vector<std::string> folders;
  ~ProcessDirs() {
    if (!::testing::UnitTest::GetInstance()->Passed() || keepDirs()) return;
    for (const auto& folder : folders) {
      std::error_code ignored;
      std::filesystem::remove_all(folder, ignored);
    }
  }
};

}  // namespace

std::string processDir(const std::string& name) {
  static ProcessDirs dirs;
  dirs.folders.push_back(
      emptied(std::string(RGBDMAP_TEST_TMP) + "/" + name + "." + std::to_string(::getpid())));
  return dirs.folders.back();
}

std::string freshDir() {
  static const bool listening = (removeFreshDirsOfPassingTests(), true);
  (void)listening;
  return emptied(freshDirOf(*::testing::UnitTest::GetInstance()->current_test_info()));
}

int run(const std::string& command, std::string* output) {
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return -1;
  std::array<char, 4096> buffer{};
  std::string text;
  while (std::size_t n = std::fread(buffer.data(), 1, buffer.size(), pipe))
    text.append(buffer.data(), n);
  const int status = ::pclose(pipe);
  if (output) *output = text;
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

MapCloud loadMap(const std::string& path) {
  MapCloud cloud;
  EXPECT_EQ(pcl::io::loadPCDFile(path, cloud), 0) << path;
  return cloud;
}

std::size_t countOccurrences(const std::string& text, const std::string& needle) {
  std::size_t count = 0;
  for (std::size_t at = text.find(needle); at != std::string::npos;
       at = text.find(needle, at + needle.size()))
    ++count;
  return count;
}

double jsonNumber(const std::string& json, const std::string& key) {
  // Plain search, not <regex>: GCC 12 warns inside <regex> in sanitizer builds.
  const std::string quoted = "\"" + key + "\":";
  const std::size_t at = json.find(quoted);
  if (at == std::string::npos) {
    ADD_FAILURE() << "no \"" << key << "\" in " << json;
    return std::nan("");
  }
  return std::strtod(json.c_str() + at + quoted.size(), nullptr);
}

}  // namespace rgbdmap::test

#include <signal.h>
#include <spawn.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <limits>
#include <sstream>
#include <thread>

extern char** environ;

namespace rgbdmap::test {

Process::Process(const std::vector<std::string>& argv, const std::string& log_path) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log_path.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  // The child must not inherit a blocked signal mask from gtest's thread.
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  sigset_t none;
  sigemptyset(&none);
  posix_spawnattr_setsigmask(&attr, &none);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGMASK);
  pid_t pid = -1;
  if (posix_spawn(&pid, argv[0].c_str(), &actions, &attr, args.data(), environ) != 0) pid = -1;
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  pid_ = pid;
}

Process::~Process() {
  if (pid_ > 0 && !reaped_) {
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, &status_, 0);
  }
}

void Process::signal(int sig) const {
  if (pid_ > 0) ::kill(pid_, sig);
}

bool Process::running() {
  if (pid_ <= 0 || reaped_) return false;
  if (::waitpid(pid_, &status_, WNOHANG) == pid_) reaped_ = true;
  return !reaped_;
}

int Process::wait(double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (running()) {
    if (std::chrono::steady_clock::now() > deadline) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, &status_, 0);
      reaped_ = true;
      return -1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (pid_ <= 0) return -1;
  if (WIFEXITED(status_)) return WEXITSTATUS(status_);
  if (WIFSIGNALED(status_)) return 128 + WTERMSIG(status_);
  return -1;
}

bool waitUntil(const std::function<bool()>& condition, double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (!condition()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return true;
}

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string writeOnce(const std::string& folder,
                      const std::function<void(const std::string&)>& write) {
  namespace fs = std::filesystem;
  const std::string done = folder + "/.complete";
  if (fs::exists(done)) return folder;
  fs::create_directories(fs::path(folder).parent_path());
  // CTest runs tests in parallel processes: the first to ask writes, the others wait for it (an
  // advisory lock, which the kernel releases if the writer dies).
  const int lock = ::open((folder + ".lock").c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (lock >= 0) ::flock(lock, LOCK_EX);
  if (!fs::exists(done)) {
    // Written under a private name and renamed into place when complete: a writer cut short
    // leaves nothing a later test would take for the whole.
    const std::string mine = emptied(folder + "." + std::to_string(::getpid()));
    write(mine);
    if (!::testing::Test::HasFatalFailure()) {
      std::ofstream(mine + "/.complete") << "\n";
      std::error_code ec;
      fs::remove_all(folder, ec);
      fs::rename(mine, folder, ec);
      if (ec) ADD_FAILURE() << "cannot move " << mine << " to " << folder << ": " << ec.message();
    }
    fs::remove_all(mine);
  }
  if (lock >= 0) ::close(lock);
  return folder;
}

std::string sharedDir() {
  const char* shared = std::getenv("RGBDMAP_TEST_SYNTHETIC_DIR");
  return shared && *shared ? std::string(shared) : std::string(RGBDMAP_TEST_TMP) + "/synthetic";
}

std::string sharedSynthetic(const std::string& name, const std::string& synth_options) {
  // scripts/test.sh points the sanitizer builds at the release build's sequences: rendering them
  // again under a sanitizer tests nothing new (the renderer has tests of its own) and took most
  // of a sanitized test's time.
  return writeOnce(sharedDir() + "/" + name, [&](const std::string& folder) {
    std::string output;
    // synth writes into a folder of its own.
    std::filesystem::remove_all(folder);
    if (run(binary() + " synth --out " + folder + synth_options, &output) != 0)
      FAIL() << "rgbdmap synth" << synth_options << " failed:\n" << output;
  });
}

std::string copySequence(const std::string& source, const std::string& target) {
  namespace fs = std::filesystem;
  fs::create_directories(target);
  for (const char* list : {"rgb.txt", "depth.txt", "groundtruth.txt"})
    fs::copy_file(source + "/" + list, target + "/" + list, fs::copy_options::overwrite_existing);
  for (const char* folder : {"rgb", "depth"})
    fs::create_directory_symlink(source + "/" + folder, target + "/" + folder);
  return target;
}

std::string sequenceTail(const std::string& source, std::size_t first, const std::string& target) {
  return sequenceSlice(source, first, std::numeric_limits<std::size_t>::max(), target);
}

std::string sequenceSlice(const std::string& source, std::size_t first, std::size_t end,
                          const std::string& target) {
  namespace fs = std::filesystem;
  fs::create_directories(target);
  for (const char* list : {"rgb.txt", "depth.txt"}) {
    std::ifstream in(source + "/" + list);
    std::ofstream out(target + "/" + list);
    std::size_t frame = 0;
    for (std::string line; std::getline(in, line);) {
      if (line.empty() || line[0] == '#') {
        out << line << "\n";
        continue;
      }
      if (frame >= first && frame < end) out << line << "\n";
      ++frame;
    }
  }
  fs::copy_file(source + "/groundtruth.txt", target + "/groundtruth.txt");
  for (const char* folder : {"rgb", "depth"})
    fs::create_directory_symlink(source + "/" + folder, target + "/" + folder);
  return target;
}

StalledWrite::StalledWrite(const std::string& path) {
  EXPECT_EQ(::mkfifo(path.c_str(), 0644), 0) << path << ": " << std::strerror(errno);
  fd_ = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  EXPECT_GE(fd_, 0) << path << ": " << std::strerror(errno);
  // The smallest pipe: a few kB of the file fill it.
  if (fd_ >= 0) {
    EXPECT_GT(::fcntl(fd_, F_SETPIPE_SZ, 4096), 0) << std::strerror(errno);
  }
}

StalledWrite::~StalledWrite() {
  if (fd_ >= 0) ::close(fd_);
}

bool StalledWrite::begun() const {
  pollfd p{fd_, POLLIN, 0};
  return ::poll(&p, 1, 0) == 1 && (p.revents & POLLIN) != 0;
}

}  // namespace rgbdmap::test
