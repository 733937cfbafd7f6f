"""Two sheets of a surface closer than the retriangulation's error (cow.off: the tail along its rear;
two vertices at one point on an unwelded seam): the conservative transfer keeps each sheet's detail on its own sheet."""

import numpy as np
import pytest

from curvdetail.curvature import curvature_detail
from curvdetail.curvature.testing import grid
from curvdetail.remesh.transfer import transfer_curvature

GAP = 0.05          # between the two source sheets (the grids are 1 x 1)


def facing_sheets(offset_a):
    """Sheet A (z = offset_a, normal +z) under sheet B (z = GAP, normal -z): they face each other."""
    V, F = grid(9, 9)
    A = V.copy()
    A[:, 2] = offset_a
    B = V.copy()
    B[:, 2] = GAP
    return np.vstack([A, B]), np.vstack([F, F[:, ::-1] + len(V)]), len(V)


def test_detail_stays_on_its_own_sheet_when_the_other_is_closer():
    # target: sheet A moved 1.5 gaps away from B, so every sample of source A is closer to target B
    # (1 gap) than to target A (1.5 gaps); target B faces the other way and must not take A's detail
    Vs, Fs, n = facing_sheets(0.0)
    Vt, Ft, _ = facing_sheets(-1.5 * GAP)
    Ds = curvature_detail(Vs, Fs)
    Dt = transfer_curvature(Vs, Fs, Vt, Ft)
    # each target sheet is its source sheet moved along its normal: the closest point below a flat
    # sheet is the point straight below, so each sheet gets its own detail back, to rounding
    assert np.abs(Ds[:n]).max() > 0.1                     # the boundary's in-plane detail: something to carry
    np.testing.assert_allclose(Dt[:n], Ds[:n], atol=1e-12)
    np.testing.assert_allclose(Dt[n:], Ds[n:], atol=1e-12)


def seam(tilt, shift=0.0, n=9):
    """Sheet A (y in [-1, 0], z = 0) and sheet B (y in [0, 1], turned by ``tilt`` about the x axis and
    moved ``shift`` along it) meeting along the segment x in [0, 1] of the x axis without sharing a
    vertex there: an unwelded seam, where a sample is at distance 0 from both sheets."""
    V, F = grid(n, n)
    A = V - [0.0, 1.0, 0.0]
    B = np.column_stack([V[:, 0] + shift, np.cos(tilt) * V[:, 1], np.sin(tilt) * V[:, 1]])
    return np.vstack([A, B]), np.vstack([F, F + len(V)]), len(V)


@pytest.mark.parametrize("tilt", [0.0, 0.5])
def test_detail_on_an_unwelded_seam_stays_on_its_own_sheet(tilt):
    # each flat sheet's detail sums to zero (its boundary conormals close up); a sample of the seam
    # put on the other sheet would carry its in-plane measure (length 1 along the seam) across,
    # leaving a sum of 1 on each sheet
    Vs, Fs, _ = seam(tilt)
    Vt, Ft, n = seam(tilt, shift=0.05, n=7)            # another triangulation, B slid along the seam
    Dt = transfer_curvature(Vs, Fs, Vt, Ft)
    np.testing.assert_allclose(Dt[:n].sum(axis=0), 0.0, atol=1e-12)
    np.testing.assert_allclose(Dt[n:].sum(axis=0), 0.0, atol=1e-12)


def test_a_seamed_mesh_onto_itself_gets_its_own_detail_back():
    Vs, Fs, _ = seam(0.5)
    np.testing.assert_allclose(transfer_curvature(Vs, Fs, Vs, Fs), curvature_detail(Vs, Fs), atol=1e-12)
