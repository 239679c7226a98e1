#include "graph/channel_graph.hpp"

#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

namespace rover::graph {

ProcessChannels ParseListing(const std::string& text, const std::string& source) {
  ProcessChannels p;
  std::istringstream in(text);
  std::string line;
  int number = 0;
  auto bad = [&] {
    return std::runtime_error(source + ": line " + std::to_string(number) + ": \"" + line +
                              "\": expected process NAME, publishes CHANNEL [when ...] or subscribes CHANNEL");
  };
  while (std::getline(in, line)) {
    ++number;
    if (line.empty()) continue;
    std::istringstream words(line);
    std::string verb, channel, when_word;
    words >> verb >> channel;
    const bool named = !channel.empty();
    if (verb == "process" && named && p.name.empty()) {
      p.name = channel;
    } else if (verb == "publishes" && named) {
      Publication pub{channel, ""};
      if (words >> when_word) {
        if (when_word != "when") throw bad();
        std::getline(words >> std::ws, pub.when);
      }
      p.publishes.push_back(pub);
    } else if (verb == "subscribes" && named) {
      p.subscribes.push_back(channel);
    } else {
      throw bad();
    }
  }
  if (p.name.empty()) throw std::runtime_error(source + ": no `process NAME` line in its --channels listing");
  return p;
}

std::string ListText(const std::vector<ProcessChannels>& set) {
  std::ostringstream os;
  for (const auto& p : set) {
    for (const auto& pub : p.publishes) {
      os << p.name << " publishes " << pub.channel << (pub.when.empty() ? "" : " when " + pub.when) << "\n";
    }
    for (const auto& s : p.subscribes) os << p.name << " subscribes " << s << "\n";
  }
  return os.str();
}

namespace {

std::string Quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '\n') {
      out += "\\n";  // a line break in a label
      continue;
    }
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

std::string ChannelNode(const std::string& channel) { return Quoted("ch:" + channel); }

// Who publishes and who subscribes each channel.
struct Edges {
  std::map<std::string, std::vector<std::pair<std::string, std::string>>> publishers;  // channel -> (process, when)
  std::map<std::string, std::vector<std::string>> subscribers;
  std::set<std::string> channels;
};

Edges Collect(const std::vector<ProcessChannels>& set) {
  Edges e;
  for (const auto& p : set) {
    for (const auto& pub : p.publishes) {
      e.publishers[pub.channel].emplace_back(p.name, pub.when);
      e.channels.insert(pub.channel);
    }
    for (const auto& s : p.subscribes) {
      e.subscribers[s].push_back(p.name);
      e.channels.insert(s);
    }
  }
  return e;
}

void WriteChannels(std::ostringstream& os, const Edges& e, std::size_t set_size, const DotOptions& options,
                   bool* outside_used) {
  for (const auto& channel : e.channels) {
    const auto pubs = e.publishers.count(channel) ? e.publishers.at(channel)
                                                  : std::vector<std::pair<std::string, std::string>>{};
    const auto subs = e.subscribers.count(channel) ? e.subscribers.at(channel) : std::vector<std::string>{};
    const bool all_pub = !options.every_edge && set_size > 1 && pubs.size() == set_size;
    const bool all_sub = !options.every_edge && set_size > 1 && subs.size() == set_size;
    std::string label = channel;
    if (all_pub) label += "\n(from every process)";
    if (all_sub) label += "\n(to every process)";
    os << "  " << ChannelNode(channel) << " [label=" << Quoted(label) << "];\n";
    if (!all_pub) {
      for (const auto& [process, when] : pubs) {
        os << "  " << Quoted(process) << " -> " << ChannelNode(channel);
        if (!when.empty()) os << " [style=dashed, tooltip=" << Quoted("when " + when) << "]";
        os << ";\n";
      }
    }
    if (!all_sub) {
      for (const auto& process : subs) os << "  " << ChannelNode(channel) << " -> " << Quoted(process) << ";\n";
    }
    if (pubs.empty()) {
      os << "  outside -> " << ChannelNode(channel) << " [style=dotted];\n";
      *outside_used = true;
    }
    if (subs.empty()) {
      os << "  " << ChannelNode(channel) << " -> outside [style=dotted];\n";
      *outside_used = true;
    }
  }
}

}  // namespace

std::string Dot(const std::vector<ProcessChannels>& set, const DotOptions& options) {
  std::ostringstream os;
  os << "digraph rover {\n"
     << "  graph [rankdir=TB, fontname=Helvetica, fontsize=12, labelloc=t, nodesep=0.15, ranksep=0.9, label="
     << Quoted(options.title + "\nboxes: processes; ellipses: channels; dashed: published only in some runs"
                               " (tooltip); dotted: outside the set") << "];\n"
     << "  node [fontname=Helvetica, fontsize=10, shape=ellipse, style=filled, fillcolor=\"#f2f2f2\", color=\"#888888\"];\n"
     << "  edge [color=\"#555555\", arrowsize=0.6];\n";
  for (const auto& p : set) {
    os << "  " << Quoted(p.name)
       << " [shape=box, style=\"rounded,filled,bold\", fillcolor=\"#d6e6f5\", color=\"#2f5d8a\", fontsize=12];\n";
  }
  bool outside_used = false;
  WriteChannels(os, Collect(set), set.size(), options, &outside_used);
  if (outside_used) {
    os << "  outside [shape=note, fillcolor=\"#fff5d6\", label=\"outside the set\\n(operators' tools, consoles,\\n"
          "recorder, tests)\"];\n";
  }
  os << "}\n";
  return os.str();
}

}  // namespace rover::graph
