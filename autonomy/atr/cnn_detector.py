"""CNN detector: the ONNX CenterNet-style model run with onnxruntime.

Model contract (written by ``sim.training``, checked on load):
- input ``image`` float32 (1, 1, H, W), / 255: the fan resized to W x H (``cv2.INTER_AREA``),
  or, with metadata ``input_transform`` = ``pad``, the fan at native resolution in the
  top-left corner with zeros beyond (H, W at least the fan's; no resize, boxes in fan px);
  with ``input_transform`` = ``fan_uint8``, input ``image`` uint8 (1, 1, H_fan, W_fan): the
  fan itself, the graph casting, scaling and padding it (``scripts/atr_fold_input.py`` folds
  a ``pad`` model so, with the same outputs bit for bit);
- outputs ``heatmap`` (1, C, H/s, W/s), ``size`` (1, 2, H/s, W/s), ``offset`` (1, 2, H/s, W/s)
  as described in :mod:`autonomy.atr.centernet_decode`;
- metadata ``auvsim_atr_format`` = ``centernet-v1``, ``class_names`` (JSON list), ``stride``,
  ``fan_width_px``, ``fan_height_px`` (the fan size the model was trained on), optional
  ``input_transform`` (``resize``, the default, ``pad`` or ``fan_uint8``).
"""

from __future__ import annotations

import json
import threading
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from autonomy.atr.centernet_decode import decode_centernet
from autonomy.atr.detector import check_frame, to_detections
from autonomy.atr.model_file import ModelFileError
from autonomy.atr.nms import nms
from autonomy.messages import Detection, FlsFrame

MODEL_FORMAT = "centernet-v1"
#: How a fan becomes the model input (metadata ``input_transform``).
INPUT_TRANSFORMS = ("resize", "pad", "fan_uint8")
INPUT_NAME = "image"
OUTPUT_NAMES = ("heatmap", "size", "offset")
#: The input scale of the model contract (uint8 grey level -> [0, 1]).
INPUT_SCALE = np.float32(1.0 / 255.0)


class CnnDetector:
    """Runs an ATR ONNX model on FLS frames.

    :meth:`detect` runs the model through an onnxruntime IO binding on buffers allocated once
    (the resized fan, the model input and the three outputs): no allocation or copy of images
    per frame. A lock makes concurrent calls on one instance take turns.

    Args:
        model_path: ONNX file following the contract in the module docstring.
        score_threshold: operating threshold on the peak score.
        nms_iou: IoU above which a lower-scored box of the same class is dropped.
        max_detections: cap on detections per frame.
        intra_op_threads: onnxruntime CPU threads (1 = one core).
        classes: keep only these class names (None = all).
        accept_any_fan_size: take fans of any size (resized to the model input like the
            trained one; detections on such fans are not validated). False: :meth:`detect`
            raises on a fan of another size than :attr:`fan_hw`.

    Raises:
        ModelFileError: the file is missing, not ONNX, or breaks the model contract.
    """

    def __init__(self, model_path: str | Path, score_threshold: float = 0.5, nms_iou: float = 0.3,
                 max_detections: int = 50, intra_op_threads: int = 1,
                 classes: tuple[str, ...] | None = None, accept_any_fan_size: bool = False) -> None:
        import onnxruntime as ort

        self.model_path = Path(model_path)
        if not self.model_path.is_file():
            raise ModelFileError(f"ATR model file {self.model_path}: no such file")
        opts = ort.SessionOptions()
        opts.intra_op_num_threads = int(intra_op_threads)
        opts.inter_op_num_threads = 1
        opts.execution_mode = ort.ExecutionMode.ORT_SEQUENTIAL
        opts.log_severity_level = 3
        try:
            self._session = ort.InferenceSession(str(self.model_path), sess_options=opts,
                                                 providers=["CPUExecutionProvider"])
        except Exception as exc:  # onnxruntime raises several private exception types
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            raise ModelFileError(f"ATR model file {self.model_path}: not a valid ONNX model ({first})") from None
        meta = self._session.get_modelmeta().custom_metadata_map
        if meta.get("auvsim_atr_format") != MODEL_FORMAT:
            raise ModelFileError(
                f"ATR model file {self.model_path}: metadata auvsim_atr_format is "
                f"{meta.get('auvsim_atr_format')!r}, expected {MODEL_FORMAT!r}"
            )
        try:
            self.class_names: tuple[str, ...] = tuple(json.loads(meta["class_names"]))
            self.stride = int(meta["stride"])
            self.fan_hw = (int(meta["fan_height_px"]), int(meta["fan_width_px"]))
        except (KeyError, ValueError) as exc:
            raise ModelFileError(f"ATR model file {self.model_path}: bad or missing metadata ({exc})") from exc
        inputs = self._session.get_inputs()
        if len(inputs) != 1 or inputs[0].name != INPUT_NAME or len(inputs[0].shape) != 4:
            raise ModelFileError(f"ATR model file {self.model_path}: expected one input {INPUT_NAME!r} (1, 1, H, W)")
        shape = inputs[0].shape
        if not all(isinstance(v, int) for v in shape[1:]) or shape[1] != 1:
            raise ModelFileError(f"ATR model file {self.model_path}: input must be (1, 1, H, W) with fixed H, W; got {shape}")
        self.input_hw = (int(shape[2]), int(shape[3]))
        self.input_transform = meta.get("input_transform", "resize")
        if self.input_transform not in INPUT_TRANSFORMS:
            raise ModelFileError(f"ATR model file {self.model_path}: metadata input_transform is "
                                 f"{self.input_transform!r}, expected one of {', '.join(INPUT_TRANSFORMS)}")
        if self.input_transform == "pad" and (self.fan_hw[0] > self.input_hw[0] or self.fan_hw[1] > self.input_hw[1]):
            raise ModelFileError(f"ATR model file {self.model_path}: input {self.input_hw} is smaller than the "
                                 f"fan {self.fan_hw} it pads")
        if self.input_transform == "fan_uint8" and self.input_hw != self.fan_hw:
            raise ModelFileError(f"ATR model file {self.model_path}: input {self.input_hw} is not the fan "
                                 f"{self.fan_hw} it takes as it is")
        if self.input_transform in ("pad", "fan_uint8") and accept_any_fan_size:
            raise ModelFileError(f"ATR model file {self.model_path}: reads fans at native resolution "
                                 f"({self.fan_hw[1]} x {self.fan_hw[0]} px) and cannot take fans of any size")
        out_names = tuple(o.name for o in self._session.get_outputs())
        if set(OUTPUT_NAMES) - set(out_names):
            raise ModelFileError(f"ATR model file {self.model_path}: outputs {out_names}, expected {OUTPUT_NAMES}")
        self.score_threshold = float(score_threshold)
        self.nms_iou = float(nms_iou)
        self.max_detections = int(max_detections)
        self._keep = None if classes is None else set(classes)
        self.accept_any_fan_size = bool(accept_any_fan_size)
        self._check_source = f"CNN detector ({self.model_path})"
        self._bind_buffers()

    def _bind_buffers(self) -> None:
        """Allocate the per-frame buffers and bind them to the session (a model whose outputs
        are not float32 of fixed shapes runs through :meth:`raw_outputs` instead)."""
        self._lock = threading.Lock()
        self._binding = None
        outs = {o.name: o for o in self._session.get_outputs()}
        shapes = {name: outs[name].shape for name in OUTPUT_NAMES}
        in_type = "tensor(uint8)" if self.input_transform == "fan_uint8" else "tensor(float)"
        if not (all(isinstance(v, int) for shape in shapes.values() for v in shape)
                and self._session.get_inputs()[0].type == in_type
                and all(outs[name].type == "tensor(float)" for name in OUTPUT_NAMES)):
            return
        self._small = np.empty(self.input_hw, np.uint8)
        in_dtype = np.uint8 if self.input_transform == "fan_uint8" else np.float32
        self._input = np.zeros((1, 1, *self.input_hw), in_dtype)
        self._outputs = {name: np.zeros(shapes[name], np.float32) for name in OUTPUT_NAMES}
        self._binding = self._session.io_binding()
        self._binding.bind_input(INPUT_NAME, "cpu", 0, in_dtype, self._input.shape, self._input.ctypes.data)
        for name, buf in self._outputs.items():
            self._binding.bind_output(name, "cpu", 0, np.float32, buf.shape, buf.ctypes.data)

    def preprocess(self, fan: NDArray[np.uint8]) -> NDArray[np.float32]:
        """Fan image (H_fan, W_fan) uint8 -> model input (1, 1, H, W): float32, or the uint8 fan
        itself for a model that scales and pads inside its graph (``fan_uint8``)."""
        h, w = self.input_hw
        if self.input_transform == "fan_uint8":
            return np.ascontiguousarray(fan, dtype=np.uint8)[None, None]
        if self.input_transform == "pad":
            out = np.zeros((1, 1, h, w), np.float32)
            np.multiply(fan, INPUT_SCALE, out=out[0, 0, :fan.shape[0], :fan.shape[1]], dtype=np.float32)
            return out
        small = cv2.resize(fan, (w, h), interpolation=cv2.INTER_AREA)
        # one pass: uint8 -> float32 and the scale (the same float32 products as astype, then *)
        return np.multiply(small, INPUT_SCALE, dtype=np.float32)[None, None]

    def raw_outputs(self, fan: NDArray[np.uint8]) -> dict[str, NDArray[np.float32]]:
        """Model outputs for one fan image, by name, batch dimension removed (new arrays, from a
        plain ``session.run`` on :meth:`preprocess`: the reference for :meth:`detect`'s path)."""
        outs = self._session.run(list(OUTPUT_NAMES), {INPUT_NAME: self.preprocess(fan)})
        return {k: v[0] for k, v in zip(OUTPUT_NAMES, outs)}

    def _run_bound(self, fan: NDArray) -> dict[str, NDArray[np.float32]]:
        """Preprocess ``fan`` into the bound input and run the model; returns the outputs by
        name, batch dimension removed (views of the bound buffers: valid until the next run,
        so only under ``self._lock``)."""
        if self._binding is None:
            return self.raw_outputs(fan)
        if self.input_transform == "fan_uint8" and fan.shape == self.fan_hw and fan.dtype == np.uint8:
            np.copyto(self._input[0, 0], fan)  # the graph casts, scales and pads
        elif self.input_transform == "pad" and fan.shape == self.fan_hw and fan.dtype == np.uint8:
            # the padding stays zero from allocation; only the fan's corner is written
            np.multiply(fan, INPUT_SCALE, out=self._input[0, 0, :fan.shape[0], :fan.shape[1]])
        elif self.input_transform == "resize" and fan.ndim == 2 and fan.dtype == np.uint8:
            h, w = self.input_hw
            cv2.resize(fan, (w, h), dst=self._small, interpolation=cv2.INTER_AREA)
            np.multiply(self._small, INPUT_SCALE, out=self._input[0, 0])
        else:  # anything else the plain path accepts, through it
            self._input[...] = self.preprocess(fan)
        self._session.run_with_iobinding(self._binding)
        return {k: v[0] for k, v in self._outputs.items()}

    def detect_boxes(self, fan: NDArray[np.uint8], score_threshold: float | None = None
                     ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]]:
        """Boxes in fan px (N, 4), scores (N,), class ids (N,) after NMS, by decreasing score."""
        thr = self.score_threshold if score_threshold is None else float(score_threshold)
        with self._lock:
            out = self._run_bound(fan)
            boxes, scores, cls = decode_centernet(out["heatmap"], out["size"], out["offset"], self.stride,
                                                  thr, self.max_detections)
        if boxes.shape[0] == 0:
            return boxes, scores, cls
        if self.input_transform == "resize":
            sx = fan.shape[1] / self.input_hw[1]
            sy = fan.shape[0] / self.input_hw[0]
            # Input px (pixel centres at integers) -> fan px.
            boxes = (boxes + 0.5) * np.array([sx, sy, sx, sy]) - 0.5
        if boxes.shape[0] == 1:  # nothing to suppress
            return boxes, scores, cls
        keep = nms(boxes, scores, self.nms_iou, cls)
        return boxes[keep], scores[keep], cls[keep]

    def detect(self, frame: FlsFrame, score_threshold: float | None = None) -> list[Detection]:
        """Detections on one frame, by decreasing score.

        Raises:
            ValueError: ``frame.fan`` is not a 2-D uint8 image of the model's fan size (of any
                size with ``accept_any_fan_size``).
        """
        fan = getattr(frame, "fan", None)
        if not (isinstance(fan, np.ndarray) and fan.shape == self.fan_hw and fan.dtype == np.uint8):
            check_frame(frame, None if self.accept_any_fan_size else self.fan_hw, source=self._check_source)
        boxes, scores, cls = self.detect_boxes(fan, score_threshold)
        names = [self.class_names[i] for i in cls]
        if self._keep is not None:
            sel = [i for i, n in enumerate(names) if n in self._keep]
            boxes, scores, names = boxes[sel], scores[sel], [names[i] for i in sel]
        return to_detections(frame, boxes, scores, names)
