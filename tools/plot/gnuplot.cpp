#include "plot/gnuplot.hpp"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace rover::plot {
namespace {

// Runs gnuplot with `args` in `workdir`, its output and errors to `log_path`; the exit
// status, or -1 when it could not be started.
int Run(const std::vector<std::string>& args, const std::string& workdir, const std::string& log_path) {
  const pid_t pid = fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    const int fd = open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      dup2(fd, STDOUT_FILENO);
      dup2(fd, STDERR_FILENO);
      close(fd);
    }
    const int null_in = open("/dev/null", O_RDONLY);
    if (null_in >= 0) dup2(null_in, STDIN_FILENO);
    if (!workdir.empty() && chdir(workdir.c_str()) != 0) _exit(126);
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execvp("gnuplot", argv.data());
    _exit(127);  // not installed
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return -1;
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// The first line of gnuplot's log that says what went wrong.
std::string FirstError(const std::string& log_path) {
  std::ifstream in(log_path);
  std::string line, first;
  while (std::getline(in, line)) {
    if (line.find_first_not_of(" \t^") == std::string::npos) continue;
    if (first.empty()) first = line;
    if (line.find("rror") != std::string::npos || line.find("line ") != std::string::npos) {
      return line;
    }
  }
  return first;
}

}  // namespace

std::string PngTerminal() {
  const std::string log = "/dev/null";
  if (Run({"gnuplot", "-e", "set terminal pngcairo"}, "", log) == 0) return "pngcairo";
  if (Run({"gnuplot", "-e", "set terminal png"}, "", log) == 0) return "png";
  return "";
}

std::string RunGnuplot(const std::string& workdir, const std::string& script) {
  std::string log = script;
  if (log.size() > 3 && log.compare(log.size() - 3, 3, ".gp") == 0) log.resize(log.size() - 3);
  log += ".log";
  const int code = Run({"gnuplot", script}, workdir, workdir + "/" + log);
  std::error_code ec;
  if (code == 0) {
    if (std::filesystem::file_size(workdir + "/" + log, ec) == 0) std::filesystem::remove(workdir + "/" + log, ec);
    return "";
  }
  if (code == 127) return "gnuplot is not installed (Debian package gnuplot-nox; ./rover setup installs it)";
  const std::string first = FirstError(workdir + "/" + log);
  return "gnuplot " + script + " failed (exit " + std::to_string(code) + ")" +
         (first.empty() ? "" : ": " + first) + " (see " + workdir + "/" + log + ")";
}

std::string Quoted(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '\\' || c == '"') out += '\\';
    if (c == '\n') out += "\\n";
    else out += c;
  }
  return out + "\"";
}

std::string Num(double v) {
  if (!std::isfinite(v)) return "?";
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

}  // namespace rover::plot
