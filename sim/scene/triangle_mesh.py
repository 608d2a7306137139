"""The closed triangle mesh of a seabed object (:class:`TriangleMesh`), numpy only.

Its own module so that both mesh builders return it: :mod:`sim.scene.target_meshes` (the
numpy primitives, which hands debris shapes on) and :mod:`sim.scene.debris_meshes` (the
trimesh-built debris), with no import of one by the other in both directions (a cycle).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray


@dataclass
class TriangleMesh:
    """A closed triangle mesh.

    Attributes:
        vertices: (n, 3) float64 positions, m.
        faces: (m, 3) int64 vertex indices, counter-clockwise seen from outside.
    """

    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]
    _moments: NDArray[np.float64] | None = field(default=None, repr=False, compare=False)

    def _volume_moments(self) -> NDArray[np.float64]:
        """(volume, first moments x, y, z) by the divergence theorem over the faces (Eberly,
        "Polyhedral Mass Properties", 2002), summed in the order trimesh's ``mass_properties`` uses."""
        if self._moments is None:
            tri = self.vertices[self.faces]
            edges = tri[:, 1:, :] - tri[:, :2, :]
            crosses = np.cross(edges[:, 0], edges[:, 1])
            f1 = tri[:, 0, :] + tri[:, 1, :] + tri[:, 2, :]
            f2 = tri[:, 0, :] ** 2 + tri[:, 1, :] ** 2 + tri[:, 0, :] * tri[:, 1, :] + tri[:, 2, :] * f1
            integral = np.zeros((4, len(f1)))
            integral[0] = crosses[:, 0] * f1[:, 0]
            integral[1:4] = (crosses * f2).T
            self._moments = integral.sum(axis=1) / np.array([6, 24, 24, 24], dtype=np.float64)
        return self._moments

    @property
    def volume(self) -> float:
        """Enclosed volume, m^3 (negative when the faces are wound inwards)."""
        return float(self._volume_moments()[0])

    @property
    def center_mass(self) -> NDArray[np.float64]:
        """(3,) centroid of the enclosed volume (uniform density), m."""
        m = self._volume_moments()
        return m[1:4] / m[0]

    @property
    def bounds(self) -> NDArray[np.float64]:
        """(2, 3) lowest and highest vertex coordinates, m."""
        return np.array([self.vertices.min(axis=0), self.vertices.max(axis=0)])

    def translated(self, offset: tuple[float, float, float]) -> "TriangleMesh":
        return TriangleMesh(self.vertices + np.asarray(offset, dtype=np.float64), self.faces)

    def inverted(self) -> "TriangleMesh":
        """The same surface with every face's winding (hence normal) reversed."""
        return TriangleMesh(self.vertices, np.ascontiguousarray(self.faces[:, ::-1]))

    def to_trimesh(self):
        """The mesh as a ``trimesh.Trimesh`` (imports trimesh)."""
        import trimesh

        return trimesh.Trimesh(self.vertices, self.faces, process=False)
