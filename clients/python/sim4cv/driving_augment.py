"""Condition augmentation for the driving network's training (docs/driving.md,
"Every weather"): each image of a batch gets its own exposure, gamma,
contrast, colour cast and sensor noise, so the network sees more light than
the daemon's presets render. It complements domain randomisation (new
weather and hour per rendered image): that changes the scene's light, this
changes how a camera would record it.

    image = condition_augment(image, strength)   # N x 3 x H x W float, 0 ... 255

`strength` scales every range (0: unchanged, 1: the ranges below); the
draws come from torch's global generator (seeded by the trainer)."""

import torch

# natural-log ranges at strength 1: (low, high) of a uniform draw
EXPOSURE = (-1.2, 0.5)   # gain 0.30 ... 1.65: night-dark to over-exposed
GAMMA = (-0.4, 0.4)      # exponent 0.67 ... 1.49
CONTRAST = (-0.6, 0.2)   # spread about the image's mean 0.55 ... 1.22 (fog flattens, sun hardens)
CAST = (-0.15, 0.15)     # per-channel gain 0.86 ... 1.16 (white balance)
NOISE_SIGMA = 8.0        # at most, in 0 ... 255 units, per pixel and channel


def _draw(n: int, bounds, strength: float, channels: int = 1) -> torch.Tensor:
    low, high = bounds
    u = torch.rand(n, channels, 1, 1)
    return torch.exp((low + (high - low) * u) * strength)


def condition_augment(image: torch.Tensor, strength: float = 1.0) -> torch.Tensor:
    """A new tensor: `image` (N x 3 x H x W, 0 ... 255) under a random camera
    response per image. strength <= 0 returns `image` itself."""
    if strength <= 0:
        return image
    n = image.shape[0]
    x = (image / 255.0).clamp(0.0, 1.0)
    x = x ** _draw(n, GAMMA, strength)
    mean = x.mean(dim=(1, 2, 3), keepdim=True)
    x = mean + (x - mean) * _draw(n, CONTRAST, strength)
    x = x * _draw(n, EXPOSURE, strength) * _draw(n, CAST, strength, channels=3)
    x = x * 255.0 + torch.randn_like(x) * (torch.rand(n, 1, 1, 1) * NOISE_SIGMA * strength)
    return x.clamp(0.0, 255.0)
