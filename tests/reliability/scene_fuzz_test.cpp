// Fuzzing the scene reader: valid scenes (inputs/*.json and the test fixtures) mutated at random,
// as JSON trees (keys deleted, values of the wrong type, numbers NaN/inf/negative/zero/huge,
// unknown keys) and as text (truncated, random bytes, spliced). Every input must either parse or
// throw talus::Error of kind Input with a one-line message; a parsed scene must round-trip through
// scene_to_json, and some of them are stepped (they may only fail with an instability Error).
// TALUS_FUZZ_COUNT and TALUS_FUZZ_SEED override the count (100 000) and the seed.
#include "../solver/scene_fixtures.hpp"
#include "talus/core/error.hpp"
#include "talus/scene/scene_json.hpp"
#include "talus/solver/solver.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>

namespace talus {
namespace scene_fuzz_test {
namespace {

using Json = nlohmann::json;
using Rng = std::mt19937_64;

std::vector<std::string> seed_scenes() {
  std::vector<std::string> scenes;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(TALUS_SOURCE_DIR) + "/inputs")) {
    if (entry.path().extension() != ".json") continue;
    std::ifstream in(entry.path());
    scenes.emplace_back((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  }
  scenes.push_back(scene_to_json(test::bar_scene(10.0, 1.0)).dump());
  scenes.push_back(scene_to_json(test::tumbling_block_scene()).dump(1));
  scenes.push_back(scene_to_json(test::free_fall_scene("usl")).dump());
  return scenes;
}

std::size_t pick(Rng& rng, std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng); }

double random_number(Rng& rng) {
  static const double special[] = {0.0, -0.0, -1.0, 1.0, 0.5, 0.4999999, 1e-300, -1e-300, 1e300, -1e300, 1e308,
                                   90.0, 91.0, -90.0, 180.0, 1e9, 4294967296.0, 65536.0, 100000.0, 2.5, 3.0, -7.0};
  switch (pick(rng, 3)) {
    case 0: return special[pick(rng, std::size(special))];
    case 1: return std::uniform_real_distribution<double>(-10, 10)(rng);
    default: return std::ldexp(std::uniform_real_distribution<double>(-1, 1)(rng), static_cast<int>(pick(rng, 200)) - 100);
  }
}

Json random_value(Rng& rng, int depth = 0) {
  static const char* words[] = {"", "musl", "usl", "linear", "slip", "fixed", "open", "friction", "lz4", "none",
                                "drucker_prager", "linear_elastic", "rubber", "sand", "block", "x", "plane_strain",
                                "gimp", "cpgimp", "bspline2", "usf", "usavg"};
  switch (pick(rng, depth > 2 ? 6 : 8)) {
    case 0: return nullptr;
    case 1: return pick(rng, 2) == 1;
    case 2: return static_cast<long long>(pick(rng, 20)) - 5;
    case 3: return random_number(rng);
    case 4: return words[pick(rng, std::size(words))];
    case 5: return static_cast<unsigned long long>(-1);
    case 6: {
      Json a = Json::array();
      for (std::size_t i = 0, n = pick(rng, 5); i < n; ++i) a.push_back(random_value(rng, depth + 1));
      return a;
    }
    default: {
      Json o = Json::object();
      for (std::size_t i = 0, n = pick(rng, 3); i < n; ++i) o[words[pick(rng, std::size(words))]] = random_value(rng, depth + 1);
      return o;
    }
  }
}

/// Every node of the tree (pointers into it), so a mutation can pick one uniformly.
void collect(Json& j, std::vector<Json*>& nodes) {
  nodes.push_back(&j);
  if (j.is_structured())
    for (auto& child : j) collect(child, nodes);
}

void mutate_tree(Json& root, Rng& rng) {
  std::vector<Json*> nodes;
  collect(root, nodes);
  Json& node = *nodes[pick(rng, nodes.size())];
  switch (pick(rng, 7)) {
    case 0:  // delete a key or an element
      if (node.is_object() && !node.empty()) {
        auto it = node.begin();
        std::advance(it, pick(rng, node.size()));
        node.erase(it.key());
      } else if (node.is_array() && !node.empty()) {
        node.erase(pick(rng, node.size()));
      }
      break;
    case 1: node = random_value(rng); break;  // wrong type or wrong value
    case 2:                                    // a number scaled, negated, zeroed or made huge
      if (node.is_number()) {
        const double f[] = {-1.0, 0.0, 1e6, 1e-6, 2.0, 1e300};
        node = node.get<double>() * f[pick(rng, std::size(f))];
      } else {
        node = random_number(rng);
      }
      break;
    case 3:  // an unknown key
      if (node.is_object()) node["unknown_" + std::to_string(pick(rng, 3))] = random_value(rng);
      break;
    case 4:  // an array longer or shorter
      if (node.is_array()) {
        if (pick(rng, 2)) node.push_back(random_value(rng));
        else if (!node.empty()) node.erase(node.size() - 1);
      }
      break;
    case 5: node = random_number(rng); break;
    default:  // a number in place of every number of an array (e.g. a box corner far outside)
      if (node.is_array())
        for (auto& e : node) e = random_number(rng);
      break;
  }
}

void mutate_text(std::string& text, Rng& rng) {
  if (text.empty()) {
    text = "{";
    return;
  }
  switch (pick(rng, 7)) {
    case 0: text.resize(pick(rng, text.size())); break;  // truncated
    case 1: text[pick(rng, text.size())] = static_cast<char>(pick(rng, 256)); break;
    case 2: {  // random bytes inserted
      std::string bytes;
      for (std::size_t i = 0, n = 1 + pick(rng, 8); i < n; ++i) bytes += static_cast<char>(pick(rng, 256));
      text.insert(pick(rng, text.size()), bytes);
      break;
    }
    case 3: {  // a span deleted
      const std::size_t at = pick(rng, text.size());
      text.erase(at, pick(rng, 40));
      break;
    }
    case 4: {  // a span duplicated
      const std::size_t at = pick(rng, text.size());
      const std::string span = text.substr(at, pick(rng, 60));
      text.insert(pick(rng, text.size()), span);
      break;
    }
    case 5: {  // a number token replaced by what JSON does not allow or what overflows
      static const char* tokens[] = {"NaN", "nan", "Infinity", "-Infinity", "1e999", "-1e999", "1e-999", "0x10",
                                     "01", "-", "1.", ".5", "99999999999999999999999", "-0"};
      const std::size_t at = text.find_first_of("0123456789", pick(rng, text.size()));
      if (at == std::string::npos) break;
      std::size_t end = at;
      while (end < text.size() && std::string("0123456789.eE+-").find(text[end]) != std::string::npos) ++end;
      text.replace(at, end - at, tokens[pick(rng, std::size(tokens))]);
      break;
    }
    default: text = "\xef\xbb\xbf" + text; break;  // byte-order mark
  }
}

struct Outcome {
  long long parsed = 0, refused = 0, stepped = 0;
};

TEST(SceneFuzz, MutatedScenesParseOrFailWithAnInputError) {
  const char* count_env = std::getenv("TALUS_FUZZ_COUNT");
  const char* seed_env = std::getenv("TALUS_FUZZ_SEED");
  const long long count = count_env ? std::atoll(count_env) : 100000;
  Rng rng(seed_env ? std::strtoull(seed_env, nullptr, 10) : 9);
  const std::vector<std::string> seeds = seed_scenes();
  std::vector<Json> trees;
  for (const auto& s : seeds) trees.push_back(Json::parse(s));
  Outcome outcome;
  const auto start = std::chrono::steady_clock::now();
  double slowest = 0.0;
  for (long long i = 0; i < count; ++i) {
    const std::size_t which = pick(rng, seeds.size());
    std::string text;
    const std::size_t kind = pick(rng, 10);
    if (kind < 6) {  // tree mutations, 1 to 3 of them
      Json tree = trees[which];
      for (std::size_t m = 0, n = 1 + pick(rng, 3); m < n; ++m) mutate_tree(tree, rng);
      text = tree.dump(pick(rng, 2) ? -1 : 1);
      if (kind == 5) mutate_text(text, rng);
    } else {
      text = seeds[which];
      for (std::size_t m = 0, n = 1 + pick(rng, 2); m < n; ++m) mutate_text(text, rng);
    }
    const auto t0 = std::chrono::steady_clock::now();
    try {
      const Scene scene = parse_scene(text, "fuzz");
      ++outcome.parsed;
      // What the reader accepts, the writer writes back in a form the reader accepts again
      // (checked for every 8th accepted scene: the check costs more than the parse).
      if (outcome.parsed % 8 == 0) {
        const Scene again = parse_scene(scene_to_json(scene).dump(), "fuzz round trip");
        ASSERT_EQ(scene_to_json(again), scene_to_json(scene)) << "input " << i << ":\n" << text;
      }
      // Step a few of the small ones: the solver may only refuse them or report an instability.
      if (outcome.parsed % 200 == 0) {
        try {
          if (particle_count_bound(scene) <= 5000) {
            Solver solver(scene);
            for (int s = 0; s < 3 && !solver.finished(); ++s) solver.step();
            ++outcome.stepped;
          }
        } catch (const Error& e) {
          ASSERT_NE(e.kind(), Error::Kind::Io) << "input " << i << ": " << e.what() << "\n" << text;
        }
      }
    } catch (const Error& e) {
      ++outcome.refused;
      ASSERT_EQ(e.kind(), Error::Kind::Input) << "input " << i << ": " << e.what() << "\n" << text;
      const std::string what = e.what();
      ASSERT_FALSE(what.empty());
      ASSERT_EQ(what.find('\n'), std::string::npos) << "input " << i << ": message spans lines: " << what;
    } catch (const std::exception& e) {
      FAIL() << "input " << i << ": " << typeid(e).name() << ": " << e.what() << "\n" << text;
    }
    slowest = std::max(slowest, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("scene fuzz: %lld inputs in %.2f s (%lld parsed, %lld refused, %lld stepped), slowest %.3f s\n", count,
              seconds, outcome.parsed, outcome.refused, outcome.stepped, slowest);
  EXPECT_EQ(outcome.parsed + outcome.refused, count);
  EXPECT_GT(outcome.parsed, count / 50) << "mutations too destructive: few inputs exercise the validation";
  EXPECT_LT(slowest, 5.0) << "an input took too long (a hang?)";
}

}  // namespace
}  // namespace scene_fuzz_test
}  // namespace talus
