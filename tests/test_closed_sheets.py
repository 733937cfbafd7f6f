"""Two sheets of a surface that touch (cow.off: two vertices at one point on an unwelded seam): the
conservative transfer keeps each sheet's detail on its own sheet."""

import numpy as np
import pytest

from curvdetail.curvature import curvature_detail
from curvdetail.curvature.testing import grid
from curvdetail.remesh.transfer import transfer_curvature


def seam(tilt, n=9):
    """Sheet A (y in [-1, 0], z = 0) and sheet B (y in [0, 1], turned by ``tilt`` about the x axis)
    meeting along the segment x in [0, 1] of the x axis without sharing a vertex there: an unwelded
    seam (cow.off has one), where a sample is at distance 0 from both sheets."""
    V, F = grid(n, n)
    A = V - [0.0, 1.0, 0.0]
    B = np.column_stack([V[:, 0], np.cos(tilt) * V[:, 1], np.sin(tilt) * V[:, 1]])
    return np.vstack([A, B]), np.vstack([F, F + len(V)]), len(V)


@pytest.mark.parametrize("tilt", [0.0, 0.5])
def test_detail_on_an_unwelded_seam_stays_on_its_own_sheet(tilt):
    # each flat sheet's detail sums to zero (its boundary conormals close up); a sample of the seam
    # put on the other sheet would carry its in-plane measure (length 1 along the seam) across,
    # leaving a sum of 1 on each sheet
    Vs, Fs, _ = seam(tilt)
    Vt, Ft, n = seam(tilt, n=7)                        # another triangulation of the two sheets
    Dt = transfer_curvature(Vs, Fs, Vt, Ft)
    np.testing.assert_allclose(Dt[:n].sum(axis=0), 0.0, atol=1e-12)
    np.testing.assert_allclose(Dt[n:].sum(axis=0), 0.0, atol=1e-12)


def test_a_seamed_mesh_onto_itself_gets_its_own_detail_back():
    Vs, Fs, _ = seam(0.5)
    np.testing.assert_allclose(transfer_curvature(Vs, Fs, Vs, Fs), curvature_detail(Vs, Fs), atol=1e-12)
