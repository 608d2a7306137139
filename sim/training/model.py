"""Compact CenterNet-style detector in plain torch (no torchvision).

Encoder of four stride-2 stages, a light top-down path back to stride 4, and three heads:
class heat-map (sigmoid, with 3x3 max-pool peak extraction inside the graph so the exported
model emits only local maxima), log box size (w, h) in input px, and sub-cell centre offset.
"""

from __future__ import annotations

import torch
from torch import nn
from torch.nn import functional as F

STRIDE = 4
HEATMAP_PRIOR = 0.02  # initial foreground probability of the heat-map logits


def _conv_bn(c_in: int, c_out: int, stride: int = 1, k: int = 3) -> nn.Sequential:
    return nn.Sequential(nn.Conv2d(c_in, c_out, k, stride, k // 2, bias=False), nn.BatchNorm2d(c_out),
                         nn.ReLU(inplace=True))


def _dw_block(c_in: int, c_out: int, stride: int = 1) -> nn.Sequential:
    """Depthwise 3x3 + pointwise 1x1 (MobileNet-style)."""
    return nn.Sequential(
        nn.Conv2d(c_in, c_in, 3, stride, 1, groups=c_in, bias=False), nn.BatchNorm2d(c_in), nn.ReLU(inplace=True),
        nn.Conv2d(c_in, c_out, 1, bias=False), nn.BatchNorm2d(c_out), nn.ReLU(inplace=True))


class CenterNetSmall(nn.Module):
    """Input (B, 1, H, W) in [0, 1], H and W multiples of 16.

    ``light_heads``: depthwise-separable head convolutions (about 7x fewer multiply-adds in
    the stride-4 heads, which dominate the cost of the network).

    ``forward`` returns raw ``(heat_logits (B, C, H/4, W/4), size_log (B, 2, ..),
    offset (B, 2, ..))``; :meth:`export_outputs` is what the ONNX graph exposes.
    """

    def __init__(self, num_classes: int, width: int = 16, light_heads: bool = False) -> None:
        super().__init__()
        w1, w2, w3, w4 = width, 2 * width, 4 * width, 6 * width
        self.stem = nn.Sequential(_conv_bn(1, w1, 2), _dw_block(w1, w1))  # /2
        self.stage2 = nn.Sequential(_dw_block(w1, w2, 2), _dw_block(w2, w2))  # /4
        self.stage3 = nn.Sequential(_dw_block(w2, w3, 2), _dw_block(w3, w3))  # /8
        self.stage4 = nn.Sequential(_dw_block(w3, w4, 2), _dw_block(w4, w4), _dw_block(w4, w4))  # /16
        self.lat3 = nn.Conv2d(w4, w3, 1)
        self.fuse3 = _dw_block(w3, w3)
        self.lat2 = nn.Conv2d(w3, w2, 1)
        self.fuse2 = _dw_block(w2, w2)
        head = _dw_block if light_heads else _conv_bn
        self.heat = nn.Sequential(head(w2, w2), nn.Conv2d(w2, num_classes, 1))
        self.box = nn.Sequential(head(w2, w2), nn.Conv2d(w2, 4, 1))
        prior = float(torch.log(torch.tensor(HEATMAP_PRIOR / (1 - HEATMAP_PRIOR))))
        nn.init.constant_(self.heat[-1].bias, prior)
        self.num_classes = num_classes

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        x = x - 0.25  # centre the typical sonar grey level
        s1 = self.stem(x)
        s2 = self.stage2(s1)
        s3 = self.stage3(s2)
        s4 = self.stage4(s3)
        p3 = self.fuse3(s3 + F.interpolate(self.lat3(s4), size=s3.shape[-2:], mode="nearest"))
        p2 = self.fuse2(s2 + F.interpolate(self.lat2(p3), size=s2.shape[-2:], mode="nearest"))
        box = self.box(p2)
        return self.heat(p2), box[:, :2], box[:, 2:]

    def export_outputs(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """(peak heat-map in [0, 1] with non-maxima zeroed, size_log, offset)."""
        logits, size_log, offset = self.forward(x)
        heat = torch.sigmoid(logits)
        peaks = F.max_pool2d(heat, 3, 1, 1)
        return heat * (peaks == heat).to(heat.dtype), size_log, offset


class ExportWrapper(nn.Module):
    """Module whose ``forward`` is :meth:`CenterNetSmall.export_outputs` (for ONNX export)."""

    def __init__(self, model: CenterNetSmall) -> None:
        super().__init__()
        self.model = model

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        return self.model.export_outputs(x)
