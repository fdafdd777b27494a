// The model card beside a driving model (docs/driving.md, "Model card";
// clients/python/sim4cv/driving_card.py writes and reads the same file):
// model.json in the model file's folder, with the network's input size and
// goal input and the controller settings the model was selected with.
// sim4cv_drive takes the settings its command line leaves unset from it.
//
//   std::optional<ModelCard> card = ReadModelCard("models/driving/model.onnx");
//   if (card) card->CheckModel(model.height(), model.width(), model.has_goal());
#pragma once

#include <optional>
#include <stdexcept>
#include <string>

namespace sim4cv::driving {

// A card that cannot be used; the message names the file and the field.
class CardError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ModelCard {
  std::string path;  // the card file
  int height = 0;
  int width = 0;
  bool goal = false;
  // The "controller" object's settings; unset when the card leaves them out.
  std::optional<double> steer_waypoint;   // 1 ... 4 (a fraction: between two waypoints)
  std::optional<double> steer_gain;       // > 0
  std::optional<double> turn_slowdown;    // >= 0
  std::optional<double> bend_correction;  // 0 ... 1
  std::optional<double> bend_limit_m;     // > 0
  std::optional<double> speed_m_s;        // > 0, the speed cap
  std::optional<double> frame_hz;         // > 0, the evaluation's frame rate (not used when driving)

  // Throws CardError unless the card describes this network.
  void CheckModel(int model_height, int model_width, bool model_goal) const;
};

// "model.json" in the folder of `model_path`.
std::string ModelCardPath(const std::string& model_path);

// The card beside `model_path`, checked as driving_card.read checks it;
// nullopt if there is none. Throws CardError for a card that is not JSON,
// has another format, lacks the input size or holds a bad or unknown setting.
std::optional<ModelCard> ReadModelCard(const std::string& model_path);

}  // namespace sim4cv::driving
