"""ONNX export of a trained :class:`CenterNetSmall` with the metadata the detector checks."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Mapping

import onnx
import torch

from autonomy.atr.cnn_detector import INPUT_NAME, MODEL_FORMAT, OUTPUT_NAMES
from torch import nn

from sim.training.model import ExportWrapper


def export_onnx(model: nn.Module, out_path: str | Path, input_hw: tuple[int, int],
                fan_hw: tuple[int, int], class_names: list[str],
                extra_metadata: Mapping[str, str] | None = None, input_transform: str = "resize") -> Path:
    """Write ``model`` (a :data:`sim.training.model.ARCHITECTURES` model) to ``out_path``
    (fixed input (1, 1, H, W)); returns the path.

    ``input_transform``: how the detector turns a fan into the input, ``"resize"`` (INTER_AREA
    to W x H) or ``"pad"`` (the fan at native resolution in the top-left corner, zeros
    beyond), recorded in the metadata.
    """
    out_path = Path(out_path)
    out_path.parent.mkdir(parents=True, exist_ok=True)
    was_training = model.training
    model.eval()
    dummy = torch.zeros(1, 1, *input_hw)
    torch.onnx.export(ExportWrapper(model), (dummy,), str(out_path), input_names=[INPUT_NAME],
                      output_names=list(OUTPUT_NAMES), opset_version=17, dynamo=False)
    model.train(was_training)
    proto = onnx.load(str(out_path))
    meta = {"auvsim_atr_format": MODEL_FORMAT, "class_names": json.dumps(list(class_names)),
            "stride": str(model.stride),
            "input_transform": input_transform, "fan_height_px": str(fan_hw[0]), "fan_width_px": str(fan_hw[1])}
    meta.update(extra_metadata or {})
    del proto.metadata_props[:]
    for k, v in meta.items():
        entry = proto.metadata_props.add()
        entry.key, entry.value = k, str(v)
    onnx.checker.check_model(proto)
    onnx.save(proto, str(out_path))
    return out_path
