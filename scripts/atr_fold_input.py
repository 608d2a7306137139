"""Fold an ATR model's input pre-processing into its ONNX graph: the model then takes the
uint8 fan image itself (``input_transform: fan_uint8``) and does the uint8 -> float32 cast, the
1/255 scale and the zero padding to its trained input size inside onnxruntime, instead of a
NumPy pass over a float32 copy of the padded fan per frame.

The folded graph computes the same float32 input bit for bit (float32(u) * float32(1/255), then
zeros to the bottom and right, as :meth:`autonomy.atr.cnn_detector.CnnDetector.preprocess` does
for ``input_transform: pad``), so its outputs equal the original model's; the script checks that
on random fans and refuses to write otherwise.

Usage: ``python scripts/atr_fold_input.py MODEL.onnx --out FOLDED.onnx`` (needs the ``onnx``
package: the ``train`` extra). Only models with ``input_transform: pad`` can be folded.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np


def fold(src: Path, dst: Path, n_check: int = 4) -> float:
    """Write the folded model of ``src`` to ``dst``; returns the largest output difference over
    ``n_check`` random fans (0 expected). Raises ``SystemExit`` with one line on bad input."""
    import onnx
    import onnxruntime as ort
    from onnx import TensorProto, helper, numpy_helper

    from autonomy.atr.cnn_detector import INPUT_NAME, INPUT_SCALE, OUTPUT_NAMES

    model = onnx.load(str(src))
    meta = {p.key: p.value for p in model.metadata_props}
    if meta.get("input_transform") != "pad":
        raise SystemExit(f"{src}: metadata input_transform is {meta.get('input_transform')!r}; only 'pad' models fold")
    (inp,) = [i for i in model.graph.input if i.name == INPUT_NAME]
    h, w = (d.dim_value for d in inp.type.tensor_type.shape.dim[2:])
    fh, fw = int(meta["fan_height_px"]), int(meta["fan_width_px"])
    g = model.graph
    inner = "image_scaled"
    for node in g.node:  # the original graph now reads the padded float image
        node.input[:] = [inner if x == INPUT_NAME else x for x in node.input]
    g.initializer.extend([numpy_helper.from_array(np.array(INPUT_SCALE, np.float32), "input_scale"),
                          numpy_helper.from_array(np.array([0, 0, 0, 0, 0, 0, h - fh, w - fw], np.int64), "input_pads")])
    pre = [helper.make_node("Cast", [INPUT_NAME], ["image_float"], to=TensorProto.FLOAT),
           helper.make_node("Mul", ["image_float", "input_scale"], ["image_unpadded"]),
           helper.make_node("Pad", ["image_unpadded", "input_pads"], [inner], mode="constant")]
    nodes = pre + list(g.node)
    del g.node[:]
    g.node.extend(nodes)
    g.input.remove(inp)
    g.input.insert(0, helper.make_tensor_value_info(INPUT_NAME, TensorProto.UINT8, [1, 1, fh, fw]))
    for p in model.metadata_props:
        if p.key == "input_transform":
            p.value = "fan_uint8"
    onnx.checker.check_model(model)
    dst.parent.mkdir(parents=True, exist_ok=True)
    tmp = dst.with_suffix(".partial")
    onnx.save(model, str(tmp))
    a = ort.InferenceSession(str(src), providers=["CPUExecutionProvider"])
    b = ort.InferenceSession(str(tmp), providers=["CPUExecutionProvider"])
    rng = np.random.default_rng(0)
    worst = 0.0
    for _ in range(n_check):
        fan = rng.integers(0, 256, (fh, fw), dtype=np.uint8)
        x = np.zeros((1, 1, h, w), np.float32)
        np.multiply(fan, INPUT_SCALE, out=x[0, 0, :fh, :fw], dtype=np.float32)
        ra = a.run(list(OUTPUT_NAMES), {INPUT_NAME: x})
        rb = b.run(list(OUTPUT_NAMES), {INPUT_NAME: fan[None, None]})
        worst = max(worst, *(float(np.max(np.abs(u - v))) for u, v in zip(ra, rb)))
    if worst > 1e-5:
        tmp.unlink()
        raise SystemExit(f"{src}: the folded model's outputs differ from the original's by {worst:g}; not written")
    tmp.replace(dst)
    return worst


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("model", type=Path, help="ATR ONNX model with input_transform: pad")
    ap.add_argument("--out", type=Path, required=True, help="the folded model's file")
    args = ap.parse_args(argv)
    if not args.model.is_file():
        print(f"model: no file {args.model}", file=sys.stderr)
        return 2
    try:
        worst = fold(args.model, args.out)
    except SystemExit as exc:
        print(exc, file=sys.stderr)
        return 2
    print(f"wrote {args.out}: outputs within {worst:g} of {args.model}'s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
