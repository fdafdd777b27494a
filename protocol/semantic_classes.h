// The classes of CHANNEL_SEMANTIC, listed once: where Cityscapes has the
// class, its value is the Cityscapes trainId and its colour the Cityscapes
// palette, so a network trained on Cityscapes reads sim4cv frames without
// remapping; classes Cityscapes lacks come after 18, each with the trainId it
// folds into for a Cityscapes evaluation (255: ignored). Part of the wire
// contract, shared by the daemon and the C++ clients; docs/protocol.md
// ("Semantic classes") and the Python client's sim4cv.visualize list the same
// (tests/python/test_channels.py checks the Python table against this file).
#pragma once

#include <array>
#include <cstdint>
#include <string_view>


namespace sim4cv::semantic {

// X(Name, value, "name", red, green, blue, Cityscapes trainId it folds into)
#define SIM4CV_SEMANTIC_CLASSES(X)                        \
  X(Road, 0, "road", 128, 64, 128, 0)                     \
  X(Sidewalk, 1, "sidewalk", 244, 35, 232, 1)             \
  X(Building, 2, "building", 70, 70, 70, 2)               \
  X(Wall, 3, "wall", 102, 102, 156, 3)                    \
  X(Fence, 4, "fence", 190, 153, 153, 4)                  \
  X(Pole, 5, "pole", 153, 153, 153, 5)                    \
  X(TrafficLight, 6, "traffic light", 250, 170, 30, 6)    \
  X(TrafficSign, 7, "traffic sign", 220, 220, 0, 7)       \
  X(Vegetation, 8, "vegetation", 107, 142, 35, 8)         \
  X(Terrain, 9, "terrain", 152, 251, 152, 9)              \
  X(Sky, 10, "sky", 70, 130, 180, 10)                     \
  X(Person, 11, "person", 220, 20, 60, 11)                \
  X(Rider, 12, "rider", 255, 0, 0, 12)                    \
  X(Car, 13, "car", 0, 0, 142, 13)                        \
  X(Truck, 14, "truck", 0, 0, 70, 14)                     \
  X(Bus, 15, "bus", 0, 60, 100, 15)                       \
  X(Train, 16, "train", 0, 80, 100, 16)                   \
  X(Motorcycle, 17, "motorcycle", 0, 0, 230, 17)          \
  X(Bicycle, 18, "bicycle", 119, 11, 32, 18)              \
  X(LaneMarking, 19, "lane marking", 255, 255, 255, 0)    \
  X(Crosswalk, 20, "crosswalk", 200, 200, 200, 0)         \
  X(Uav, 21, "uav", 255, 128, 0, 255)                     \
  X(Obstacle, 22, "obstacle", 180, 100, 40, 4)            \
  X(Unlabelled, 255, "unlabelled", 0, 0, 0, 255)

enum class SemanticClass : uint8_t {
#define SIM4CV_SEMANTIC_ENUM(NAME, VALUE, ...) k##NAME = VALUE,
  SIM4CV_SEMANTIC_CLASSES(SIM4CV_SEMANTIC_ENUM)
#undef SIM4CV_SEMANTIC_ENUM
};

struct SemanticClassInfo {
  SemanticClass id;
  std::string_view name;
  std::array<uint8_t, 3> colour;
  uint8_t cityscapes_train_id;  // what a Cityscapes evaluation counts it as; 255: ignored
};

inline constexpr std::array kSemanticClasses = {
#define SIM4CV_SEMANTIC_INFO(NAME, VALUE, TEXT, R, G, B, FOLD) \
  SemanticClassInfo{SemanticClass::k##NAME, TEXT, {R, G, B}, FOLD},
    SIM4CV_SEMANTIC_CLASSES(SIM4CV_SEMANTIC_INFO)
#undef SIM4CV_SEMANTIC_INFO
};

// Where nothing is drawn: the clear value of the semantic render target.
static_assert(static_cast<int>(SemanticClass::kSky) == 10, "server/render/channels/semantic.cpp clears to 10");

}  // namespace sim4cv::semantic
