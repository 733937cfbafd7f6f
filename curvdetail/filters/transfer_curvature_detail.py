"""Filter ``transfer_curvature_detail``: carry curvature detail from one layer to another."""

import numpy as np

from ..curvature import curvature_detail, mixed_voronoi_area
from ..curvature.robust_laplacian import LAPLACIANS, source_detail
from .compute_curvature_detail import LAPLACIAN_DESCRIPTION, signed_mean_curvature
from .detail_attributes import DETAIL, load_detail, store_detail
from .errors import FilterError, FilterParameterError
from .meshset import layer_id, mesh_arrays, set_vertex_quality, vertex_attribute
from .parameters import Parameter
from .registry import PAPER, filter


def planar_map(location, parameterization, default="harmonic"):
    """The ``parameterization`` a filter passes on: None where ``location`` is not 'uv', where a
    value other than the default is a mistake (it would be ignored) and refused."""
    if location == "uv":
        return parameterization
    if parameterization != default:
        raise FilterParameterError(f"parameterization={parameterization!r} applies to location='uv' only "
                                   f"(location={location!r} uses no planar map); pass location='uv' or "
                                   "leave parameterization at its default.", parameter="parameterization")
    return None


def check_retriangulation(Vs, Fs, Vt, Ft, source, target):
    """`curvdetail.remesh.check_retriangulation` (boundary within ``RETRIANGULATION_TOLERANCE``,
    every vertex within ``SURFACE_TOLERANCE`` of the source) in the filter's words: FilterError
    with ``parameter`` 'targetmesh' and the check's ``value``, ``count`` and ``first`` (target
    vertices)."""
    from ..remesh import RemeshError
    from ..remesh import check_retriangulation as check

    try:
        check(Vs, Fs, Vt, Ft, advice=f"pass a retriangulation of layer {source} as the target (e.g. from "
                                     "generate_curvature_remeshing)")
    except RemeshError as exc:
        raise FilterError(f"layer {target}: {exc.problem}", parameter="targetmesh", value=exc.value,
                          hint=exc.hint, count=exc.count, first=exc.first) from None


@filter(
    name="transfer_curvature_detail",
    category="Curvature detail",
    description=f"""
        Carry the curvature detail of the source layer (a manifold surface; a disk-topology
        patch for location 'uv') over to the target layer (a retriangulation of it: as many
        boundary loops, its boundary vertices within 0.1 % of the diagonal of the source's
        boundary and every vertex within 3 % of the source's surface, else refused), the transfer
        step of the paper's remeshing experiment. The detail carried is the source's stored 'curvature_detail' where it holds
        one (from compute_curvature_detail, kept while its vertices were moved; refused if the
        source was retriangulated since, as apply_curvature_reconstruction refuses it), else the
        detail of its current geometry; the returned 'detail_source' says which ('stored' or
        'computed'). 'pointwise' (the paper) interpolates the source's intensive mean curvature
        normal K at each target vertex and multiplies it by the target's own mixed Voronoi area;
        'conservative' moves the extensive detail D as a measure so that its total is kept.
        Target vertices are located on the source by the closest point in space ('closest') or in
        a shared planar parameterization with the boundary on the unit circle by arc length
        ('uv'). Stores the target's 'curvature_detail', 'curvature_normal' (D / A) and
        'curvature_area' attributes, ready for apply_curvature_reconstruction, and sets its vertex
        quality to the transferred signed mean curvature. A source with zero-area triangles (scans)
        gives its detail by the mollified Laplacian (laplacian 'auto' or 'robust'; its caps are
        flipped away for locating points); the returned 'laplacian' says which ran (None for
        stored detail). {PAPER}, section "Remeshing", Fig. 3.
    """,
    parameters=[
        Parameter("sourcemesh", "mesh", 0,
                  "layer whose curvature detail is carried over: its stored 'curvature_detail' "
                  "where it holds one, else the detail of its current geometry"),
        Parameter("targetmesh", "mesh", None, "layer that receives it (default: the current one)"),
        Parameter("method", "str", "conservative",
                  "'conservative' (detail moved as a measure, totals kept) or 'pointwise' "
                  "(the paper: K interpolated, times the target's area)",
                  choices=("conservative", "pointwise")),
        Parameter("location", "str", "closest",
                  "where a target vertex lies on the source: 'closest' point in space or 'uv' "
                  "(shared planar parameterization)", choices=("closest", "uv")),
        Parameter("parameterization", "str", "harmonic",
                  "planar map for location='uv' (only): own cotangent 'harmonic' map, pymeshlab's "
                  "'meshlab_harmonic' or 'lscm'", choices=("harmonic", "meshlab_harmonic", "lscm")),
        Parameter("laplacian", "str", "auto", "where the detail is computed, the source's Laplacian: "
                  + LAPLACIAN_DESCRIPTION.removeprefix("the mesh's Laplacian: "), choices=LAPLACIANS),
    ],
)
def transfer_curvature_detail(ms, *, sourcemesh, targetmesh, method, location, parameterization, laplacian):
    from ..remesh import check_surface, parameterize, transfer_curvature
    from ..remesh.transfer import squashed_in_plane

    parameterization = planar_map(location, parameterization)
    source = layer_id(ms, sourcemesh, "sourcemesh")
    target = layer_id(ms, targetmesh, "targetmesh")
    if source == target:
        raise FilterError(f"sourcemesh and targetmesh are both layer {source}", parameter="targetmesh",
                          hint="load or generate the retriangulation as another layer (e.g. layer 1)")
    Vs, Fs = mesh_arrays(ms, source)
    Vt, Ft = mesh_arrays(ms, target)
    # zero-area caps (scans): the robust detail, and the caps flipped away for locating points
    Fl, Dr, used = source_detail(Vs, Fs, laplacian)
    Vs, Fl, _ = check_surface(Vs, Fl, f"the source (layer {source})")   # 'uv': parameterize asks for disks
    Vt, Ft, _ = check_surface(Vt, Ft, f"the target (layer {target})")
    check_retriangulation(Vs, Fl, Vt, Ft, source, target)
    # stored detail outlives moved vertices (the editing use); a broken stamp is refused in load_detail
    stored = vertex_attribute(ms, source, DETAIL, "point") is not None
    Ds = load_detail(ms, source, Fs) if stored else curvature_detail(Vs, Fs) if Dr is None else Dr
    figures = {"method": method, "location": location, "detail_source": "stored" if stored else "computed",
               **(dict.fromkeys(used, None) if stored else used)}
    uv = None
    if location == "uv":
        UVs, UVt, info = parameterize(Vs, Fl, Vt, Ft, method=parameterization)
        # a collapsed triangle named in the filter's words (the transfer's own refusal names uv[1]
        # (UVt) and parameterize(...), which a filter user never sees)
        other = "parameterization='harmonic' or " if parameterization != "harmonic" else ""
        for which, layer, UV, T in (("source", source, UVs, Fl), ("target", target, UVt, Ft)):
            squashed_in_plane(UV, T, f"the {parameterization} parameterization of the {which} (layer {layer})",
                              f"Use {other}location='closest' (no planar map).", FilterError)
        uv = (UVs, UVt)
        figures.update(parameterization=parameterization, flipped_source=info["flipped_source"],
                       flipped_target=info["flipped_target"],
                       boundary_mismatch=info["boundary_mismatch"])
    Dt = transfer_curvature(Vs, Fl, Vt, Ft, method=method, location=location, uv=uv,
                            detail=Ds if stored or Dr is not None else None)
    At = mixed_voronoi_area(Vt, Ft)
    Kt = Dt / At[:, None]
    store_detail(ms, target, Ft, Dt, Kt, At)
    set_vertex_quality(ms, target, signed_mean_curvature(Vt, Ft, Kt))
    scale = max(np.abs(Ds).sum(), np.finfo(float).tiny)
    figures.update(
        source_vertices=int(Vs.shape[0]), target_vertices=int(Vt.shape[0]),
        detail_total_source=[float(x) for x in Ds.sum(axis=0)],
        detail_total_target=[float(x) for x in Dt.sum(axis=0)],
        detail_total_gap=float(np.linalg.norm(Dt.sum(axis=0) - Ds.sum(axis=0)) / scale),
    )
    return figures
