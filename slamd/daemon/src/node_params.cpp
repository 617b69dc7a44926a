// slamd's node parameters (node_params.h).
#include "whiskeye/slamd/node_params.h"

#include <cstdio>
#include <cstring>

namespace whiskeye::slamd {
namespace {

// The keys of slamd's channels, inputs first. The same key names as whiskerd's lcm.channel_* for the
// same channel (channel_cycle).
struct ChannelKey {
  const char* key;
  std::string NodeChannels::*name;
};
constexpr ChannelKey kChannelKeys[] = {
    {"channel_cycle", &NodeChannels::cycle}, {"channel_camera", &NodeChannels::camera},
    {"channel_odometry", &NodeChannels::odometry}, {"channel_pose", &NodeChannels::pose},
    {"channel_event", &NodeChannels::event}, {"channel_match", &NodeChannels::match},
    {"channel_map", &NodeChannels::map}, {"channel_status", &NodeChannels::status},
};

// A refused name as an error line can hold it: at most 40 characters, a byte outside printable
// ASCII as \xNN, and the length of a longer one.
std::string shown(const std::string& name) {
  std::string out = "\"";
  for (std::size_t i = 0; i < name.size() && i < 40; ++i) {
    const auto c = static_cast<unsigned char>(name[i]);
    if (c >= 0x20 && c < 0x7f && c != '"' && c != '\\') {
      out += static_cast<char>(c);
    } else {
      char hex[5];
      std::snprintf(hex, sizeof hex, "\\x%02x", c);
      out += hex;
    }
  }
  out += name.size() > 40 ? "...\" (" + std::to_string(name.size()) + " characters)" : "\"";
  return out;
}

// Each channel a valid name, none of them another's, and none the stack's channel of another type
// (GROUND_TRUTH, SIM_FAULT, DRIVER_STATUS, ...: common/channels.h): slamd would write into it, or
// read a type it cannot decode.
void check_channels(const ParamNode& node, const NodeChannels& c) {
  const NodeChannels defaults;
  for (std::size_t i = 0; i < std::size(kChannelKeys); ++i) {
    const char* key = kChannelKeys[i].key;
    const std::string& name = c.*kChannelKeys[i].name;
    if (!channels::valid_name(name)) {
      node.fail(key, "= " + shown(name) + " is no channel name: 1 to " + std::to_string(channels::kMaxNameLength) +
                         " of A-Z a-z 0-9 _ - / (LCM's limit; it subscribes by regular expression)");
    }
    const char* type = channels::type_of(defaults.*kChannelKeys[i].name);
    if (const char* taken = channels::type_of(name); taken != nullptr && std::strcmp(taken, type) != 0) {
      node.fail(key, "= \"" + name + "\" is the stack's channel of " + taken + ", not of " + type +
                         " (common/channels.h): give slamd's channel a name of its own");
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (c.*kChannelKeys[j].name == name) {
        node.fail(key, "= \"" + name + "\" is '" + node.path_of(kChannelKeys[j].key) +
                           "' too: each of slamd's channels needs a name of its own");
      }
    }
  }
}

}  // namespace

void load(const ParamNode& node, NodeParams& p) {
  node.get("camera_tolerance_s", p.sync.camera_tolerance_s, 0.0, 2.0);
  node.get("max_wait_s", p.sync.max_wait_s, 0.05, 30.0);
  node.get("camera_buffer_s", p.sync.camera_buffer_s, 0.0, 60.0);
  node.get("camera_buffer", p.sync.camera_buffer, 1, 1000);
  node.get("max_jump_s", p.sync.max_jump_s, 1.0, 86400.0);
  node.get("odometry_buffer", p.sync.odometry_buffer, 100, 10000000);
  node.get("map_period_s", p.map_period_s, 0.0, 3600.0);
  for (const ChannelKey& k : kChannelKeys) node.get(k.key, p.channels.*k.name);
  check_channels(node, p.channels);
}

}  // namespace whiskeye::slamd
