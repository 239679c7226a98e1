#include "plot/gnuplot.hpp"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

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

namespace {

// Where a line of `line` longer than `max_chars` breaks: just after the last separator that
// leaves the head at most `max_chars` long, preferring "; " to ", " to " ". npos: nowhere.
std::size_t BreakPoint(const std::string& line, std::size_t max_chars) {
  for (const char* sep : {"; ", ", ", " "}) {
    const std::size_t n = std::char_traits<char>::length(sep);
    std::size_t best = std::string::npos;
    for (std::size_t at = line.find(sep); at != std::string::npos && at + n - 1 <= max_chars; at = line.find(sep, at + 1)) {
      if (at > 0) best = at + n;
    }
    if (best != std::string::npos && best > max_chars / 3) return best;  // no stub lines
  }
  const std::size_t space = line.find(' ', max_chars);  // a word longer than a line
  return space == std::string::npos ? std::string::npos : space + 1;
}

}  // namespace

std::string WrapTitle(const std::string& text, std::size_t max_chars) {
  std::string out;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    std::string line = text.substr(start, end - start);
    while (line.size() > max_chars) {
      const std::size_t cut = BreakPoint(line, max_chars);
      if (cut == std::string::npos || cut >= line.size()) break;
      std::string head = line.substr(0, cut);
      while (!head.empty() && head.back() == ' ') head.pop_back();
      out += head + "\n";
      line = line.substr(cut);
    }
    out += line;
    if (end == text.size()) break;
    out += "\n";
    start = end + 1;
  }
  return out;
}

std::size_t TitleChars(int width_px) { return static_cast<std::size_t>(std::max(20, width_px / 7)); }

std::string Num(double v) {
  if (!std::isfinite(v)) return "?";
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

}  // namespace rover::plot
