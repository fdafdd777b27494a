"""Writes the ONNX models and reference outputs for the C++ WaypointModel
test (tests/unit/driving_model_test.cpp); not a pytest module.

    /usr/bin/python3 tests/python/driving_onnx_export.py OUT_DIR

Needs clients/python on PYTHONPATH. Exit status 77 (and a message) when
torch is missing, so the C++ test can skip. Writes into OUT_DIR:

* small.onnx: an untrained WaypointNet(90, 160) through export_onnx;
  small_image.bin (90x160x3 uint8 RGB, random), small_out.bin (torch's 8
  float32 outputs for it); small_big_image.bin (180x320x3 uint8 RGB) and
  small_big_out.bin (torch's outputs for it shrunk to 160x90 with
  cv2.INTER_AREA, what WaypointModel.Predict does with a larger frame).
* goal.onnx: WaypointNet(90, 160, use_goal=True); goal_image.bin and
  goal_out_{m1,0,p1}.bin: torch's outputs with goal -1, 0, +1.
* image_norm.onnx: WaypointNet(90, 160, use_goal=True, input_norm="image")
  (each image normalised by its own statistics: an InstanceNormalization
  node); image_norm_image.bin and image_norm_out.bin (goal +1).
* four_outputs.onnx: a tiny net with input image [1, 3, 90, 160] and output
  waypoints [1, 4]; gray_input.onnx: input image [1, 1, 90, 160], output
  waypoints [1, 8] (both to be refused).
"""

import os
import sys

import numpy as np

try:
    import torch
    import torch.nn as nn
except ImportError:
    print("torch is missing (install python3-torch)")
    sys.exit(77)

import cv2
from sim4cv.driving_net import WaypointNet, export_onnx


def torch_out(model, image_hwc, goal=None):
    x = torch.from_numpy(image_hwc.transpose(2, 0, 1)[None].astype(np.float32))
    with torch.no_grad():
        if goal is None:
            return model(x).numpy().astype(np.float32).reshape(-1)
        return model(x, torch.tensor([[goal]], dtype=torch.float32)).numpy().astype(np.float32).reshape(-1)


class Tiny(nn.Module):
    def __init__(self, channels, outputs):
        super().__init__()
        self.conv = nn.Conv2d(channels, 4, 5, stride=4)
        self.fc = nn.Linear(4, outputs)

    def forward(self, image):
        return self.fc(self.conv(image).mean(dim=(2, 3)))


def export_tiny(path, channels, outputs):
    model = Tiny(channels, outputs).eval()
    with torch.no_grad():
        torch.onnx.export(model, (torch.zeros(1, channels, 90, 160),), path, opset_version=11,
                          input_names=["image"], output_names=["waypoints"])


def main(out):
    os.makedirs(out, exist_ok=True)
    torch.manual_seed(1)
    rng = np.random.default_rng(7)
    path = lambda name: os.path.join(out, name)

    small = WaypointNet(90, 160).eval()
    export_onnx(small, path("small.onnx"))
    image = rng.integers(0, 256, size=(90, 160, 3), dtype=np.uint8)
    image.tofile(path("small_image.bin"))
    torch_out(small, image).tofile(path("small_out.bin"))
    big = rng.integers(0, 256, size=(180, 320, 3), dtype=np.uint8)
    big.tofile(path("small_big_image.bin"))
    torch_out(small, cv2.resize(big, (160, 90), interpolation=cv2.INTER_AREA)).tofile(path("small_big_out.bin"))

    goal = WaypointNet(90, 160, use_goal=True).eval()
    export_onnx(goal, path("goal.onnx"))
    image = rng.integers(0, 256, size=(90, 160, 3), dtype=np.uint8)
    image.tofile(path("goal_image.bin"))
    for name, value in (("m1", -1.0), ("0", 0.0), ("p1", 1.0)):
        torch_out(goal, image, value).tofile(path("goal_out_%s.bin" % name))

    norm = WaypointNet(90, 160, use_goal=True, input_norm="image").eval()
    with torch.no_grad():  # a scale and offset of its own per channel, not the starting ones
        norm.norm.weight.copy_(torch.tensor([0.1, 0.2, 0.3]))
        norm.norm.bias.copy_(torch.tensor([0.05, -0.05, 0.0]))
    export_onnx(norm, path("image_norm.onnx"))
    image = (rng.integers(0, 256, size=(90, 160, 3)) * 0.3).astype(np.uint8)  # dark, as at night
    image.tofile(path("image_norm_image.bin"))
    torch_out(norm, image, 1.0).tofile(path("image_norm_out.bin"))

    export_tiny(path("four_outputs.onnx"), 3, 4)
    export_tiny(path("gray_input.onnx"), 1, 8)
    print("wrote the models to %s" % out)


if __name__ == "__main__":
    main(sys.argv[1])
