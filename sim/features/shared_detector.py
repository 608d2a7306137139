"""One ATR detector per configuration and process: the missions a process builds share it.

A CNN detector holds an onnxruntime session (the model's weights, its memory arena, the
bound input and output buffers: tens of MB) and takes a few hundred ms to build. A process
that builds many missions (an env's episodes, a batch of envs, a study's runs) would build
and hold one each. Detectors are stateless between frames (:class:`autonomy.atr.Detector`:
each ``detect`` reads only its frame; the CNN's buffers are reused under its lock), so one
per configuration serves them all with the same detections.
"""

from __future__ import annotations

from collections import OrderedDict

from autonomy.atr import build_detector
from autonomy.atr.build import model_path
from autonomy.atr.config import AtrConfig
from autonomy.atr.detector import Detector

MAX_DETECTORS = 4  # configurations kept per process (least recently used dropped)

_DETECTORS: OrderedDict[tuple, Detector] = OrderedDict()


def _key(cfg: AtrConfig) -> tuple:
    """The configuration, and for a CNN its model file's identity (a rewritten file is rebuilt)."""
    if cfg.detector != "cnn":
        return (cfg.model_dump_json(),)
    path = model_path(cfg)
    try:
        st = path.stat()
        ident = (str(path.resolve()), st.st_mtime_ns, st.st_size)
    except OSError:
        ident = (str(path),)  # missing: build_detector raises its own error, nothing is kept
    return (cfg.model_dump_json(), ident)


def shared_detector(cfg: AtrConfig) -> Detector:
    """The process's detector for ``cfg`` (built on first use by
    :func:`autonomy.atr.build_detector`, whose errors it raises)."""
    key = _key(cfg)
    det = _DETECTORS.get(key)
    if det is None:
        det = build_detector(cfg)
        _DETECTORS[key] = det
        while len(_DETECTORS) > MAX_DETECTORS:
            _DETECTORS.popitem(last=False)
    else:
        _DETECTORS.move_to_end(key)
    return det
