// doc_link_check ROOT [FILE...]: every relative link in the repository's Markdown resolves.
//
// Without FILEs it checks every tracked *.md file (`git ls-files`; without git, every *.md
// under ROOT outside build*/, out/ and node_modules/). A link is `[text](target)`,
// `![alt](target)` or a reference `[id]: target`, outside code spans and fenced code. A
// target with a scheme (https:, mailto:) is not checked; any other must name a file or
// directory that exists, relative to the file (or to ROOT when it starts with /), and its
// #anchor, when it has one and names a Markdown file, a heading of that file (GitHub's
// slugs). Each broken link is one line, `FILE:LINE: link TARGET: what is wrong`; exit 1
// when there is one, 0 when there is none, 2 for a bad argument.
#include <algorithm>
#include <array>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

std::vector<std::string> ReadLines(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(in, line)) lines.push_back(line);
  return lines;
}

// GitHub's anchor for a heading: lower case, punctuation but '-' and '_' dropped, spaces
// to '-'; a repeated heading gets -1, -2, ...
std::string Slug(const std::string& heading) {
  std::string s;
  for (unsigned char c : heading) {
    if (std::isalnum(c) || c == '-' || c == '_' || c >= 0x80) {
      s += static_cast<char>(std::tolower(c));
    } else if (c == ' ') {
      s += '-';
    }
  }
  return s;
}

bool IsFence(const std::string& line) {
  const auto start = line.find_first_not_of(' ');
  return start != std::string::npos && (line.compare(start, 3, "```") == 0 || line.compare(start, 3, "~~~") == 0);
}

std::set<std::string> Anchors(const fs::path& path) {
  std::set<std::string> anchors;
  std::map<std::string, int> seen;
  bool fenced = false;
  for (const auto& line : ReadLines(path)) {
    if (IsFence(line)) fenced = !fenced;
    if (fenced || line.empty() || line[0] != '#') continue;
    const auto text_start = line.find_first_not_of('#');
    if (text_start == std::string::npos || line[text_start] != ' ') continue;
    std::string text = line.substr(text_start + 1);
    text.erase(std::remove(text.begin(), text.end(), '`'), text.end());
    const std::string slug = Slug(text);
    const int n = seen[slug]++;
    anchors.insert(n == 0 ? slug : slug + "-" + std::to_string(n));
  }
  return anchors;
}

// The line without its code spans (`...`), which hold examples, not links.
std::string WithoutCodeSpans(const std::string& line) {
  std::string out;
  bool code = false;
  for (char c : line) {
    if (c == '`') code = !code;
    else if (!code) out += c;
  }
  return out;
}

std::string Decoded(const std::string& s) {
  std::string out;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '%' && i + 2 < s.size() && std::isxdigit(static_cast<unsigned char>(s[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(s[i + 2]))) {
      out += static_cast<char>(std::stoi(s.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      out += s[i];
    }
  }
  return out;
}

// What is wrong with `target` linked from `file`, or "".
std::string Problem(const fs::path& root, const fs::path& file, const std::string& target) {
  static const std::regex scheme("^[a-zA-Z][a-zA-Z0-9+.-]*:");
  if (target.empty() || std::regex_search(target, scheme)) return "";
  const auto hash = target.find('#');
  const std::string path_part = Decoded(target.substr(0, hash));
  const std::string anchor = hash == std::string::npos ? "" : target.substr(hash + 1);
  fs::path resolved = path_part.empty() ? file
                      : path_part[0] == '/' ? root / path_part.substr(1)
                                            : file.parent_path() / path_part;
  if (!fs::exists(resolved)) return "no such file or directory (" + fs::relative(resolved, root).string() + ")";
  if (!anchor.empty() && (resolved.extension() == ".md" || resolved.extension() == ".markdown") && fs::is_regular_file(resolved) &&
      !Anchors(resolved).count(anchor)) {
    return "no heading with the anchor #" + anchor + " in " + fs::relative(resolved, root).string();
  }
  return "";
}

int CheckFile(const fs::path& root, const fs::path& file) {
  static const std::regex inline_link(R"(\]\(\s*<?([^()<>\s]+)>?(\s+"[^"]*")?\s*\))");
  static const std::regex reference(R"(^\s{0,3}\[[^\]]+\]:\s+<?(\S+?)>?(\s.*)?$)");
  int broken = 0;
  bool fenced = false;
  const auto lines = ReadLines(file);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (IsFence(lines[i])) fenced = !fenced;
    if (fenced) continue;
    const std::string line = WithoutCodeSpans(lines[i]);
    std::vector<std::string> targets;
    for (std::sregex_iterator it(line.begin(), line.end(), inline_link), end; it != end; ++it) {
      targets.push_back((*it)[1]);
    }
    std::smatch m;
    if (std::regex_match(line, m, reference)) targets.push_back(m[1]);
    for (const auto& target : targets) {
      if (const std::string why = Problem(root, file, target); !why.empty()) {
        std::cout << fs::relative(file, root).string() << ":" << i + 1 << ": link " << target << ": " << why << "\n";
        ++broken;
      }
    }
  }
  return broken;
}

std::vector<fs::path> TrackedMarkdown(const fs::path& root) {
  std::vector<fs::path> files;
  const std::string command = "git -C '" + root.string() + "' ls-files -- '*.md' 2>/dev/null";
  if (FILE* pipe = popen(command.c_str(), "r")) {
    std::array<char, 4096> buf;
    while (fgets(buf.data(), buf.size(), pipe) != nullptr) {
      std::string name = buf.data();
      if (!name.empty() && name.back() == '\n') name.pop_back();
      if (fs::exists(root / name)) files.push_back(root / name);  // (deleted, not yet committed)
    }
    if (pclose(pipe) == 0 && !files.empty()) return files;
  }
  files.clear();
  for (auto it = fs::recursive_directory_iterator(root); it != fs::recursive_directory_iterator(); ++it) {
    const std::string name = it->path().filename().string();
    if (it->is_directory() && (name.rfind("build", 0) == 0 || name == "out" || name == "node_modules" || name == ".git")) {
      it.disable_recursion_pending();
    } else if (it->is_regular_file() && it->path().extension() == ".md") {
      files.push_back(it->path());
    }
  }
  return files;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help") {
    std::cerr << "usage: doc_link_check ROOT [FILE...]: every relative link in ROOT's tracked Markdown resolves\n";
    return argc < 2 ? 2 : 0;
  }
  const fs::path root = fs::weakly_canonical(argv[1]);
  if (!fs::is_directory(root)) {
    std::cerr << "doc_link_check: argument ROOT: " << argv[1] << ": not a directory (expected the repository root)\n";
    return 2;
  }
  std::vector<fs::path> files;
  for (int i = 2; i < argc; ++i) files.push_back(fs::weakly_canonical(argv[i]));
  if (files.empty()) files = TrackedMarkdown(root);
  int broken = 0;
  for (const auto& f : files) {
    if (!fs::is_regular_file(f)) {
      std::cerr << "doc_link_check: " << f.string() << ": no such file\n";
      return 2;
    }
    broken += CheckFile(root, f);
  }
  std::cout << "doc_link_check: " << files.size() << " Markdown files, " << broken << " broken links\n";
  return broken == 0 ? 0 : 1;
}
