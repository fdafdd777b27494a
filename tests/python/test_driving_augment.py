"""sim4cv.driving_augment: each image of a batch under its own camera
response (exposure, gamma, contrast, colour cast, noise), within the pixel
range, reproducible from torch's seed, and nothing at strength 0."""

import os
import sys

import pytest

REPO_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(REPO_ROOT, "clients", "python"))

torch = pytest.importorskip("torch")

from sim4cv.driving_augment import condition_augment  # noqa: E402


def batch():
    torch.manual_seed(0)
    return torch.rand(64, 3, 18, 32) * 200 + 20


def test_strength_zero_leaves_the_batch_as_it_is():
    image = batch()
    assert condition_augment(image, 0.0) is image


def test_every_image_gets_its_own_light_within_the_pixel_range():
    image = batch()
    out = condition_augment(image, 1.0)
    assert out.shape == image.shape
    assert float(out.min()) >= 0.0 and float(out.max()) <= 255.0
    ratio = out.mean(dim=(1, 2, 3)) / image.mean(dim=(1, 2, 3))
    # the exposure range reaches from night-dark to over-exposed: the batch spans much of it
    assert float(ratio.min()) < 0.6 and float(ratio.max()) > 1.2, ratio
    # a colour cast: the channels of one image are not scaled alike
    channel = out.mean(dim=(2, 3)) / image.mean(dim=(2, 3))
    assert float((channel.max(dim=1).values / channel.min(dim=1).values).max()) > 1.1


def test_the_same_seed_gives_the_same_batch_and_a_weaker_strength_changes_less():
    image = batch()
    torch.manual_seed(5)
    first = condition_augment(image, 1.0)
    torch.manual_seed(5)
    assert torch.equal(first, condition_augment(image, 1.0))
    torch.manual_seed(5)
    weak = condition_augment(image, 0.2)
    assert float((weak - image).abs().mean()) < float((first - image).abs().mean())
