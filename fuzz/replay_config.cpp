// Fuzz target: the replay configuration as `raycell replay/sweep` read it. The input is a
// TOML file, optionally followed by a line "%%" and lines of options:
//   set KEY=VALUE     (--set: ApplyOverride)
//   vary KEY=V1,V2    (--vary: Vary::Parse, then every combination applied to the config)
//   shard I/N         (--shard: Shard::Parse)
// Bad input must give an InputError, never a crash, a leak or a hang. Properties: the
// configuration loaded, and the one the options lead to, print as TOML that loads back equal
// (config.h); a --vary prints as text that parses back to it; its last combination is the
// config with its last value set.
#include <cstdint>
#include <string>
#include <vector>

#include "base/check.h"
#include "base/parse.h"
#include "replay/config.h"
#include "runner/sweep.h"

namespace raycell {
namespace {

void CheckRoundTrip(const ReplayConfig& config) {
  const std::string toml = ToToml(config);
  ReplayConfig again;
  try {
    again = LoadConfigFromString(toml, "<ToToml>");
  } catch (const InputError& e) {
    std::fprintf(stderr, "ToToml output does not load: %s\n%s\n", e.what(), toml.c_str());
    std::abort();
  }
  if (!(again == config)) {
    std::fprintf(stderr, "ToToml output loads as a different config:\n%s\n", toml.c_str());
    std::abort();
  }
}

void ApplyOption(ReplayConfig& config, const std::string& line) {
  if (line.rfind("set ", 0) == 0) {
    const std::string kv = line.substr(4);
    const auto eq = kv.find('=');
    if (eq == std::string::npos) return;
    ApplyOverride(config, kv.substr(0, eq), kv.substr(eq + 1));
  } else if (line.rfind("vary ", 0) == 0) {
    const Vary vary = Vary::Parse(line.substr(5));
    RAYCELL_CHECK(Vary::Parse(vary.ToString()).values == vary.values);
    const std::vector<Vary> varies{vary};
    ValidateVaries(config, varies);
    const std::size_t last = CombinationCount(varies) - 1;
    RAYCELL_CHECK(CombinationConfig(config, varies, last) ==
                  CombinationConfig(config, {Vary{vary.key, {vary.values.back()}}}, 0));
  } else if (line.rfind("shard ", 0) == 0) {
    const Shard shard = Shard::Parse(line.substr(6));
    RAYCELL_CHECK_LT(shard.index, shard.count);
  }
}

}  // namespace
}  // namespace raycell

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace raycell;
  const std::string text(reinterpret_cast<const char*>(data), size);
  const auto split = text.find("\n%%\n");
  ReplayConfig config = DefaultConfig();
  try {
    config = LoadConfigFromString(text.substr(0, split), "fuzz.toml");
    CheckRoundTrip(config);
  } catch (const InputError&) {
  }
  if (split == std::string::npos) return 0;
  for (const std::string& line : Split(text.substr(split + 4), '\n')) {
    try {
      ApplyOption(config, line);
    } catch (const InputError&) {
    }
  }
  CheckRoundTrip(config);
  return 0;
}
