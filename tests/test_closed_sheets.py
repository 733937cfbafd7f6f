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


def slit(n):
    """A bumped square with a slit along y = 1/2 from its centre to the edge x = 1: the slit's
    vertices are duplicated for the triangles above it, except its tip at the centre, which both
    sides share (cow.off's horn tips touch along such a seam from a vertex their fans share)."""
    V, F = grid(n, n)
    V[:, 2] = 0.2 * np.sin(np.pi * V[:, 0]) * np.sin(np.pi * V[:, 1])
    on_slit = np.flatnonzero(np.isclose(V[:, 1], 0.5) & (V[:, 0] > 0.5 + 1e-9))
    copy = np.arange(len(V))
    copy[on_slit] = len(V) + np.arange(on_slit.size)
    above = V[F].mean(axis=1)[:, 1] > 0.5
    F = F.copy()
    F[above] = copy[F[above]]
    return np.vstack([V, V[on_slit]]), F


@pytest.mark.parametrize("n", [9, 13])
def test_a_slit_mesh_onto_itself_gets_its_own_detail_back(n):
    # a sample on the slit is at distance 0 from both sides; near its tip the stepped sample's
    # triangle shares the tip with the other side's, which once passed it as the same side
    V, F = slit(n)
    D = curvature_detail(V, F)
    np.testing.assert_allclose(transfer_curvature(V, F, V, F, metric="target"), D, atol=1e-12 * np.abs(D).max())
