#include "driving/model_card.h"

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

namespace sim4cv::driving {
namespace {

namespace fs = std::filesystem;
using google::protobuf::Struct;
using google::protobuf::Value;

constexpr const char* kFormat = "sim4cv driving model card 1";  // driving_card.FORMAT

std::string Describe(double value) {
  std::ostringstream s;
  s << value;
  return s.str();
}

const Struct& Object(const std::string& path, const Struct& parent, const std::string& key) {
  const auto it = parent.fields().find(key);
  if (it == parent.fields().end() || !it->second.has_struct_value())
    throw CardError("model card " + path + " has no \"" + key + "\" object");
  return it->second.struct_value();
}

double Number(const std::string& path, const Struct& parent, const std::string& section, const std::string& key) {
  const auto it = parent.fields().find(key);
  if (it == parent.fields().end() || it->second.kind_case() != Value::kNumberValue)
    throw CardError("model card " + path + ": " + section + " has no number \"" + key + "\"");
  return it->second.number_value();
}

}  // namespace

std::string ModelCardPath(const std::string& model_path) {
  return (fs::absolute(model_path).parent_path() / "model.json").string();
}

std::optional<ModelCard> ReadModelCard(const std::string& model_path) {
  ModelCard card;
  card.path = ModelCardPath(model_path);
  std::ifstream in(card.path);
  if (!in) return std::nullopt;
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  Struct root;
  const auto status = google::protobuf::util::JsonStringToMessage(text, &root);
  if (!status.ok()) throw CardError("model card " + card.path + " is not readable JSON: " + status.ToString());
  const auto format = root.fields().find("format");
  if (format == root.fields().end() || format->second.string_value() != kFormat)
    throw CardError("model card " + card.path + ": expected \"format\": \"" + kFormat + "\"");
  const Struct& input = Object(card.path, root, "input");
  card.height = static_cast<int>(Number(card.path, input, "input", "height"));
  card.width = static_cast<int>(Number(card.path, input, "input", "width"));
  const auto goal = input.fields().find("goal");
  if (goal == input.fields().end() || goal->second.kind_case() != Value::kBoolValue)
    throw CardError("model card " + card.path + ": input has no true/false \"goal\"");
  card.goal = goal->second.bool_value();
  for (const auto& [key, value] : Object(card.path, root, "controller").fields()) {
    const double v = value.kind_case() == Value::kNumberValue ? value.number_value() : NAN;
    const auto bad = [&] {
      return CardError("model card " + card.path + ": controller setting \"" + key + "\" has a bad value " +
                       (std::isnan(v) ? std::string("(not a number)") : Describe(v)));
    };
    if (key == "steer_waypoint") {
      if (!(v >= 1 && v <= 4)) throw bad();
      card.steer_waypoint = v;
    } else if (key == "steer_gain" || key == "speed_m_s" || key == "frame_hz") {
      if (!(v > 0 && std::isfinite(v))) throw bad();
      (key == "steer_gain" ? card.steer_gain : key == "speed_m_s" ? card.speed_m_s : card.frame_hz) = v;
    } else if (key == "turn_slowdown") {
      if (!(v >= 0 && std::isfinite(v))) throw bad();
      card.turn_slowdown = v;
    } else if (key == "bend_correction") {
      if (!(v >= 0 && v <= 1)) throw bad();
      card.bend_correction = v;
    } else if (key == "bend_limit_m") {
      if (!(v > 0 && std::isfinite(v))) throw bad();
      card.bend_limit_m = v;
    } else {
      throw CardError("model card " + card.path + ": unknown controller setting \"" + key + "\"");
    }
  }
  return card;
}

void ModelCard::CheckModel(int model_height, int model_width, bool model_goal) const {
  if (height == model_height && width == model_width && goal == model_goal) return;
  const auto network = [](int w, int h, bool g) {
    return std::to_string(w) + "x" + std::to_string(h) + (g ? " network with a goal input" : " network");
  };
  throw CardError("model card " + path + " describes a " + network(width, height, goal) + ", but the model is a " +
                  network(model_width, model_height, model_goal));
}

}  // namespace sim4cv::driving
