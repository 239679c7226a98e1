// The picture of a process set: who publishes and who subscribes each channel, as each
// process declares it (`PROCESS --channels`, bus/process.hpp), drawn with Graphviz.
#pragma once

#include <string>
#include <vector>

namespace rover::graph {

struct Publication {
  std::string channel;
  std::string when;  // empty: published in every run; else its condition
};

// One process's channels, as it printed them with --channels.
struct ProcessChannels {
  std::string name;
  std::vector<Publication> publishes;
  std::vector<std::string> subscribes;
};

// Parses a --channels listing (`process NAME`, `publishes CHANNEL [when ...]`,
// `subscribes CHANNEL`). Throws std::runtime_error naming `source` and the line that is
// not one of those.
ProcessChannels ParseListing(const std::string& text, const std::string& source);

// One line per declaration, for scripts and the graph's test:
// `NAME publishes CHANNEL [when ...]`, `NAME subscribes CHANNEL`.
std::string ListText(const std::vector<ProcessChannels>& set);

struct DotOptions {
  std::string title;
  // Draw every edge. Otherwise an edge every process of the set has (each publishes
  // HEARTBEAT, each takes ROVER_CLOCK) is said once in the channel's label instead.
  bool every_edge = false;
};

// The set as a Graphviz digraph: processes as boxes, channels as ellipses, an arrow from
// each publisher to its channel and from the channel to each subscriber; a conditional
// publication dashed; channels fed or read only from outside the set joined to one
// "outside the set" node (operators' tools, consoles, the recorder).
std::string Dot(const std::vector<ProcessChannels>& set, const DotOptions& options);

}  // namespace rover::graph
