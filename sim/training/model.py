"""Compact CenterNet-style detectors in plain torch (no torchvision).

Two architectures, chosen by name (:data:`ARCHITECTURES`), both with three heads: class
heat-map (sigmoid, with 3x3 max-pool peak extraction inside the graph so the exported model
emits only local maxima), log box size (w, h) in input px, and sub-cell centre offset.

- ``s4`` (:class:`CenterNetSmall`, the v2 model): four stride-2 stages, a light top-down path
  back to stride 4, heads at stride 4; fed the fan resized to the input.
- ``s8`` (:class:`CenterNetS8`): a 4 x 4 stride-4 patch stem (no convolution at stride 2 or 4 beyond it), stages at strides 8 and 16, one
  top-down step, heads at stride 8; meant for the fan at its native resolution, zero-padded to
  a multiple of 16 (no resize), so an object keeps its 9-16 px in a 1-2 cell footprint.
"""

from __future__ import annotations

import torch
from torch import nn
from torch.nn import functional as F

STRIDE = 4
HEATMAP_PRIOR = 0.02  # initial foreground probability of the heat-map logits


def _conv_bn(c_in: int, c_out: int, stride: int = 1, k: int = 3, padding: int | None = None) -> nn.Sequential:
    pad = k // 2 if padding is None else padding
    return nn.Sequential(nn.Conv2d(c_in, c_out, k, stride, pad, bias=False), nn.BatchNorm2d(c_out),
                         nn.ReLU(inplace=True))


def _dw_block(c_in: int, c_out: int, stride: int = 1) -> nn.Sequential:
    """Depthwise 3x3 + pointwise 1x1 (MobileNet-style)."""
    return nn.Sequential(
        nn.Conv2d(c_in, c_in, 3, stride, 1, groups=c_in, bias=False), nn.BatchNorm2d(c_in), nn.ReLU(inplace=True),
        nn.Conv2d(c_in, c_out, 1, bias=False), nn.BatchNorm2d(c_out), nn.ReLU(inplace=True))


def _add_heads(model: nn.Module, c: int, num_classes: int, light_heads: bool) -> None:
    """The heat-map (``model.heat``, bias at the foreground prior) and box (``model.box``:
    log size and offset) heads on ``c`` channels."""
    head = _dw_block if light_heads else _conv_bn
    model.heat = nn.Sequential(head(c, c), nn.Conv2d(c, num_classes, 1))
    model.box = nn.Sequential(head(c, c), nn.Conv2d(c, 4, 1))
    prior = float(torch.log(torch.tensor(HEATMAP_PRIOR / (1 - HEATMAP_PRIOR))))
    nn.init.constant_(model.heat[-1].bias, prior)
    model.num_classes = num_classes


class CenterNetSmall(nn.Module):
    stride = STRIDE

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
        _add_heads(self, w2, num_classes, light_heads)

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


class CenterNetS8(nn.Module):
    """Input (B, 1, H, W) in [0, 1], H and W multiples of 16; heads at stride 8.

    ``forward`` returns raw ``(heat_logits (B, C, H/8, W/8), size_log (B, 2, ..),
    offset (B, 2, ..))``; :meth:`export_outputs` is what the ONNX graph exposes.
    """

    stride = 8

    def __init__(self, num_classes: int, width: int = 24, light_heads: bool = True) -> None:
        super().__init__()
        w1, w2, w3 = width, 2 * width, 4 * width
        self.stem = _conv_bn(1, w1, 4, k=4, padding=0)  # /4: one 4 x 4 patch per cell
        self.stage8 = nn.Sequential(_dw_block(w1, w2, 2), _dw_block(w2, w2))  # /8
        self.stage16 = nn.Sequential(_dw_block(w2, w3, 2), _dw_block(w3, w3), _dw_block(w3, w3))  # /16
        self.lat8 = nn.Conv2d(w3, w2, 1)
        self.fuse8 = _dw_block(w2, w2)
        _add_heads(self, w2, num_classes, light_heads)

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        x = x - 0.25  # centre the typical sonar grey level
        s8 = self.stage8(self.stem(x))
        s16 = self.stage16(s8)
        p8 = self.fuse8(s8 + F.interpolate(self.lat8(s16), size=s8.shape[-2:], mode="nearest"))
        box = self.box(p8)
        return self.heat(p8), box[:, :2], box[:, 2:]

    export_outputs = CenterNetSmall.export_outputs


#: Architecture name -> model class (``train-atr --arch``).
ARCHITECTURES = {"s4": CenterNetSmall, "s8": CenterNetS8}


class ExportWrapper(nn.Module):
    """Module whose ``forward`` is :meth:`CenterNetSmall.export_outputs` (for ONNX export)."""

    def __init__(self, model: nn.Module) -> None:
        super().__init__()
        self.model = model

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        return self.model.export_outputs(x)
