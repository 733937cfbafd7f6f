"""Small analytic meshes for tests, examples, docs and benchmarks (numpy only)."""

import numpy as np


def grid(nx, ny, *, size=(1.0, 1.0)):
    """Flat triangulated rectangle ``[0, size_x] x [0, size_y]`` in the z = 0 plane.

    Returns ``(V, F)``: ``nx * ny`` vertices (x fastest), ``2 (nx-1)(ny-1)`` triangles, normals +z.
    """
    x = np.linspace(0.0, size[0], nx)
    y = np.linspace(0.0, size[1], ny)
    X, Y = np.meshgrid(x, y)
    V = np.column_stack([X.ravel(), Y.ravel(), np.zeros(nx * ny)])
    i, j = np.meshgrid(np.arange(nx - 1), np.arange(ny - 1))
    a = (j * nx + i).ravel()
    b, c, d = a + 1, a + nx, a + nx + 1
    F = np.concatenate([np.column_stack([a, b, d]), np.column_stack([a, d, c])])
    return V, F


def icosphere(radius=1.0, subdivisions=3):
    """Sphere of ``radius`` centred at the origin: a subdivided icosahedron, outward normals.

    ``10 * 4**subdivisions + 2`` vertices, all exactly at distance ``radius``.
    """
    t = (1.0 + 5 ** 0.5) / 2.0
    V = np.array([[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
                  [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]], float)
    F = np.array([[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
                  [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
                  [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]])
    V /= np.linalg.norm(V, axis=1, keepdims=True)
    for _ in range(int(subdivisions)):
        E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
        uniq, inv = np.unique(E, axis=0, return_inverse=True)
        inv = inv.reshape(-1)
        mid = V[uniq[:, 0]] + V[uniq[:, 1]]
        mid /= np.linalg.norm(mid, axis=1, keepdims=True)
        m = F.shape[0]
        e01, e12, e20 = (inv[:m] + len(V), inv[m:2 * m] + len(V), inv[2 * m:] + len(V))
        V = np.vstack([V, mid])
        F = np.concatenate([np.column_stack([F[:, 0], e01, e20]), np.column_stack([F[:, 1], e12, e01]),
                            np.column_stack([F[:, 2], e20, e12]), np.column_stack([e01, e12, e20])])
    return radius * V, F


def cylinder(radius=1.0, height=1.0, n_around=64, n_along=33, *, z0=None):
    """Open cylinder of ``radius`` around the z axis, z from ``z0`` (default ``-height/2``) to
    ``z0 + height``; ``n_around * n_along`` vertices on rings, two boundary circles, outward normals."""
    z0 = -height / 2.0 if z0 is None else z0
    theta = 2.0 * np.pi * np.arange(n_around) / n_around
    z = z0 + height * np.linspace(0.0, 1.0, n_along)
    T, Z = np.meshgrid(theta, z)
    V = np.column_stack([radius * np.cos(T.ravel()), radius * np.sin(T.ravel()), Z.ravel()])
    i, j = np.meshgrid(np.arange(n_around), np.arange(n_along - 1))
    a = (j * n_around + i).ravel()
    b = (j * n_around + (i + 1) % n_around).ravel()
    c, d = a + n_around, b + n_around
    F = np.concatenate([np.column_stack([a, b, d]), np.column_stack([a, d, c])])
    return V, F


def disk(n_rings=20, radius=1.0):
    """Flat triangulated disk (z = 0) of ``n_rings`` rings around a centre vertex, ring r with
    ``6 r`` vertices, triangulated between consecutive rings by angle; normals +z."""
    pts = [np.zeros((1, 2))]
    angles = [np.zeros(1)]
    for r in range(1, n_rings + 1):
        k = 6 * r
        a = 2.0 * np.pi * (np.arange(k) + 0.5 * (r % 2)) / k
        pts.append(np.column_stack([np.cos(a), np.sin(a)]) * (radius * r / n_rings))
        angles.append(a)
    offsets = np.cumsum([0] + [p.shape[0] for p in pts])
    faces = []
    for r in range(n_rings):
        inner = offsets[r] + np.arange(pts[r].shape[0])
        outer = offsets[r + 1] + np.arange(pts[r + 1].shape[0])
        if r == 0:
            faces.append(np.column_stack([np.full(outer.size, inner[0]), outer, np.roll(outer, -1)]))
            continue
        # merge the two rings by angle: a strip triangulation
        ai = np.mod(angles[r], 2 * np.pi)
        ao = np.mod(angles[r + 1], 2 * np.pi)
        oi, oo = np.argsort(ai), np.argsort(ao)
        inner, outer, ai, ao = inner[oi], outer[oo], ai[oi], ao[oo]
        i = o = 0
        ni, no = inner.size, outer.size
        tris = []
        while i < ni or o < no:
            # advance the ring whose next vertex comes first in angle
            next_i = ai[(i + 1) % ni] + (2 * np.pi if i + 1 >= ni else 0)
            next_o = ao[(o + 1) % no] + (2 * np.pi if o + 1 >= no else 0)
            if o < no and (i >= ni or next_o <= next_i):
                tris.append([inner[i % ni], outer[o % no], outer[(o + 1) % no]])
                o += 1
            else:
                tris.append([inner[i % ni], outer[o % no], inner[(i + 1) % ni]])
                i += 1
        faces.append(np.array(tris))
    V = np.column_stack([np.vstack(pts), np.zeros(offsets[-1])])
    return V, np.vstack(faces).astype(np.int64)
