"""The driving case study's network (docs/driving.md, "Network and
controller"): a small CNN that predicts the 4 waypoints (v1 h1 ... v4 h4, in
metres, the order of labels.csv) from one RGB image, optionally given a goal
(-1 turn left, 0 follow the lane / straight, +1 turn right).

    model = WaypointNet(height=180, width=320, use_goal=False)
    out = model(images)                 # images: N x 3 x H x W float, 0 ... 255 (uint8 range)
    export_onnx(model, "net.onnx", 180, 320)
    run = load_onnx_with_opencv("net.onnx")
    waypoints = run(rgb_uint8_hxwx3)    # numpy (8,): v1 h1 v2 h2 v3 h3 v4 h4

The input normalisation is inside the model, so the ONNX file takes raw RGB
values as float32 and needs no preprocessing but the HWC -> CHW transpose:
"fixed" (x / 255 - 0.5, the shipped model) or "image" (each image's channels
brought to zero mean and unit spread, then a learned scale and offset: an
InstanceNormalization, which makes a dark night frame and a bright noon frame
of the same road look alike to the convolutions).

Needs torch (python3-torch); load_onnx_with_opencv needs only cv2 and numpy.
"""

import warnings
from typing import Callable, Optional, Sequence, Tuple

import numpy as np

try:  # the OpenCV runner must work without torch
    import torch
    import torch.nn as nn
    import torch.nn.functional as F
except ImportError:  # pragma: no cover - exercised only without torch
    torch = None
    nn = None
    F = None

OUTPUTS = 8  # v1 h1 v2 h2 v3 h3 v4 h4
DEFAULT_HEIGHT, DEFAULT_WIDTH = 180, 320
SMALL_HEIGHT, SMALL_WIDTH = 90, 160
# (out_channels, kernel, stride) of the 5 convolutions; no padding, ReLU after each.
CONV_LAYERS = ((24, 5, 2), (36, 5, 2), (48, 5, 2), (64, 3, 1), (64, 3, 1))
POOL_SIZE = (2, 4)  # rows, columns of the adaptive pooling before the FC layers
HIDDEN = 100
INPUT_NAME, GOAL_NAME, OUTPUT_NAME = "image", "goal", "waypoints"
# the input normalisations and the model card's words for them
NORMALISATIONS = {
    "fixed": "x / 255 - 0.5, inside the network",
    "image": "per image and channel (x - mean) / std, then a learned scale and offset "
             "(ONNX InstanceNormalization), inside the network",
}
# "image": the scale the learned one starts at, the spread of x / 255 - 0.5 on a
# clear-noon frame, so a network trained with "fixed" starts out nearly the same
IMAGE_NORM_SCALE = 0.16
# "image": added to the variance (0 ... 255 units) so a uniform image stays finite
IMAGE_NORM_EPS = 1.0
ONNX_OPSET = 11


def conv_output_size(height: int, width: int) -> Tuple[int, int]:
    """Rows, columns of the last convolution's feature map for an input of
    height x width (180x320 -> 15x33, 90x160 -> 4x13)."""
    for _, k, s in CONV_LAYERS:
        height = (height - k) // s + 1
        width = (width - k) // s + 1
    return height, width


def pool_window(size: int, out: int) -> Tuple[int, int]:
    """(kernel, stride) of the adaptive pooling along one axis: stride =
    size // out, kernel = size - (out - 1) * stride, so `out` windows cover
    the whole axis exactly (they overlap by kernel - stride when `out` does
    not divide `size`; they are torch's AdaptiveAvgPool2d bins when it does).
    A plain AveragePool, which ONNX opset 11 and OpenCV's DNN run as is."""
    if size < out:
        raise ValueError("feature map size %d is smaller than the pooled size %d: the image is too small" % (size, out))
    stride = size // out
    return size - (out - 1) * stride, stride


if nn is not None:

    class WaypointNet(nn.Module):
        """5 convolutions (24/36/48/64/64 channels, strides 2,2,2,1,1, ReLU),
        an adaptive average pooling to POOL_SIZE, and 2 fully connected layers
        (64*2*4 [+1 goal] -> 100, ReLU -> 8).

        Input: N x 3 x H x W float RGB in the uint8 range (0 ... 255),
        normalised inside (NORMALISATIONS[input_norm]). `height`, `width` only choose the
        default size recorded for export; any size whose last feature map
        has at least 2 x 4 cells works (e.g. 180x320 and 90x160).
        With use_goal, forward takes `goal` (N or N x 1: -1 left, 0 straight,
        +1 right), concatenated to the pooled features going into the first
        FC layer; a missing goal counts as 0."""

        def __init__(self, height: int = DEFAULT_HEIGHT, width: int = DEFAULT_WIDTH, use_goal: bool = False,
                     hidden: int = HIDDEN, outputs: int = OUTPUTS, input_norm: str = "fixed"):
            super().__init__()
            if input_norm not in NORMALISATIONS:
                raise ValueError("WaypointNet: input_norm %r is not one of %s" % (input_norm, ", ".join(NORMALISATIONS)))
            self.input_norm = input_norm
            if input_norm == "image":
                self.norm = nn.InstanceNorm2d(3, affine=True, eps=IMAGE_NORM_EPS)
                nn.init.constant_(self.norm.weight, IMAGE_NORM_SCALE)
                nn.init.zeros_(self.norm.bias)
            fh, fw = conv_output_size(height, width)
            pool_window(fh, POOL_SIZE[0])
            pool_window(fw, POOL_SIZE[1])
            self.height, self.width, self.use_goal = height, width, use_goal
            layers, cin = [], 3
            for cout, k, s in CONV_LAYERS:
                layers += [nn.Conv2d(cin, cout, k, stride=s), nn.ReLU(inplace=True)]
                cin = cout
            self.features = nn.Sequential(*layers)
            features = cin * POOL_SIZE[0] * POOL_SIZE[1]
            self.fc1 = nn.Linear(features + (1 if use_goal else 0), hidden)
            self.fc2 = nn.Linear(hidden, outputs)

        def forward(self, image, goal=None):
            return self.head(self.encode(image), goal)

        def encode(self, image):
            """The convolutions and the pooling: N x (64*2*4) features, what
            the fully connected layers see (driving_head trains those alone)."""
            x = self.norm(image) if self.input_norm == "image" else image / 255.0 - 0.5
            x = self.features(x)
            kh, sh = pool_window(int(x.shape[2]), POOL_SIZE[0])
            kw, sw = pool_window(int(x.shape[3]), POOL_SIZE[1])
            x = F.avg_pool2d(x, (kh, kw), stride=(sh, sw))
            return torch.flatten(x, 1)

        def head(self, x, goal=None):
            """The fully connected layers on encode's features (+ the goal)."""
            if self.use_goal:
                if goal is None:
                    goal = torch.zeros(x.shape[0], 1, dtype=x.dtype, device=x.device)
                if not torch.is_tensor(goal):
                    goal = torch.as_tensor(goal, dtype=x.dtype, device=x.device)
                goal = goal.to(dtype=x.dtype).reshape(-1, 1)
                x = torch.cat([x, goal], dim=1)
            elif goal is not None:
                raise ValueError("WaypointNet: a goal was given to a model built without use_goal")
            return self.fc2(F.relu(self.fc1(x)))

    def export_onnx(model: "WaypointNet", path: str, height: Optional[int] = None,
                    width: Optional[int] = None) -> None:
        """Writes `model` as ONNX (opset 11) with fixed shapes: input "image"
        [1, 3, height, width] float32 (RGB, 0 ... 255), with use_goal also
        "goal" [1, 1] float32; output "waypoints" [1, 8]. Height and width
        default to the model's."""
        height = model.height if height is None else height
        width = model.width if width is None else width
        was_training = model.training
        model.eval()
        try:
            image = torch.zeros(1, 3, height, width, dtype=torch.float32)
            if model.use_goal:
                args, names = (image, torch.zeros(1, 1, dtype=torch.float32)), [INPUT_NAME, GOAL_NAME]
            else:
                args, names = (image,), [INPUT_NAME]
            with torch.no_grad(), warnings.catch_warnings():
                # the pooling's window sizes are fixed at export: that is the contract (fixed shapes)
                warnings.simplefilter("ignore", torch.jit.TracerWarning)
                # an InstanceNorm exports as what it is, normalisation by the image's own statistics
                warnings.filterwarnings("ignore", message=".*operator 'instance_norm' is set to train=True")
                torch.onnx.export(model, args, path, opset_version=ONNX_OPSET, input_names=names,
                                  output_names=[OUTPUT_NAME], do_constant_folding=True)
        finally:
            model.train(was_training)


def onnx_input_names(path: str) -> Sequence[str]:
    """The graph's input names (needs the onnx package)."""
    import onnx
    model = onnx.load(path)
    initializers = {i.name for i in model.graph.initializer}
    return [i.name for i in model.graph.input if i.name not in initializers]


def load_onnx_with_opencv(path: str, use_goal: Optional[bool] = None) -> Callable:
    """Loads an exported WaypointNet with cv2.dnn. Returns run(image, goal=0.0)
    taking an H x W x 3 uint8 RGB image (the export's size) and returning
    numpy float32 (8,): v1 h1 v2 h2 v3 h3 v4 h4. `goal` is used only by a
    model with a "goal" input. `use_goal` None: read from the file's inputs
    (needs the onnx package); give it to avoid that dependency."""
    import cv2
    net = cv2.dnn.readNetFromONNX(path)
    if use_goal is None:
        use_goal = GOAL_NAME in onnx_input_names(path)

    def run(image: np.ndarray, goal: float = 0.0) -> np.ndarray:
        image = np.asarray(image)
        if image.ndim != 3 or image.shape[2] != 3:
            raise ValueError("run: expected an H x W x 3 RGB image, got shape %s" % (image.shape,))
        blob = np.ascontiguousarray(image.transpose(2, 0, 1)[None].astype(np.float32))
        net.setInput(blob, INPUT_NAME)
        if use_goal:
            net.setInput(np.full((1, 1), float(goal), dtype=np.float32), GOAL_NAME)
        return np.asarray(net.forward(OUTPUT_NAME), dtype=np.float32).reshape(-1)

    return run
