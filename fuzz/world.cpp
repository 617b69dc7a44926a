// Fuzz target: the simulator's world loader (sim's load_world(), as load_world_file() calls it).
// Input: the YAML text of a world file. Seeds: fuzz/corpus/world, config/worlds/.
#include "whiskeye/common/params.h"
#include "whiskeye/sim/world.h"

#include <cstdlib>
#include <string>

using namespace whiskeye;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string yaml(reinterpret_cast<const char*>(data), size);
  try {
    const sim::World w = sim::load_world(ParamNode::from_string(yaml, "fuzz-world.yaml"));
    (void)w;
  } catch (const ParamError& e) {
    if (std::string(e.what()).empty()) std::abort();
  }
  return 0;
}
