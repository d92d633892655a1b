"""The DOE data set: assembly from job results, netCDF and CSV files, the bundled data set.

Layout (docs/CONTRACTS.md): dimensions ``t, theta, H, G`` with SI coordinates (-, rad, m, Pa);
``u_r, u_z`` (t, theta, H) [m], ``B_r, B_z`` (t, theta, H) [T], ``F_r, F_z`` (t, theta, H, G) [N];
``units`` and ``long_name`` on every variable; provenance in the global attributes (all of them
netCDF-safe: strings and numbers, structured values as JSON text).
"""

from __future__ import annotations

import functools
import json
import os
from datetime import UTC, datetime
from importlib import resources
from pathlib import Path

import numpy as np
import xarray as xr

from .._errors import MagtactError, MissingFileError
from .._files import atomic_path, file_problem
from .._files import write_csv as _write_csv
from .._versions import DOE
from .._versions import package_versions as versions
from ..study import Study, from_si
from ._cache import Entry
from ._jobs import FieldJob, PathJob

DIMS = ("t", "theta", "H", "G")
#: Variable name -> (dimensions, units, long name).
VARIABLES = {
    "u_r": (DIMS[:3], "m", "magnet displacement along the shear direction +x"),
    "u_z": (DIMS[:3], "m", "magnet displacement along z (negative: down)"),
    "B_r": (DIMS[:3], "T", "flux density at the Hall point along +x"),
    "B_z": (DIMS[:3], "T", "flux density at the Hall point along z"),
    "F_r": (DIMS, "N", "reaction force on the lower surface along +x (full body)"),
    "F_z": (DIMS, "N", "reaction force on the lower surface along z (full body)"),
}
COORDS = {"t": ("1", "non-dimensional load"), "theta": ("rad", "shear angle"),
          "H": ("m", "base height of the body"), "G": ("Pa", "shear modulus of the elastomer")}


def _csv_column(var: str, unit: str) -> str:
    """The CSV column of a variable or coordinate in a user unit: its name followed by
    ``_<unit>`` (``H_mm``), the name alone without a unit (``t``)."""
    return f"{var}_{unit}" if unit else var


#: CSV columns: name, (variable or coordinate, user unit).
CSV_COLUMNS = {_csv_column(var, unit): (var, unit) for var, unit in (
    ("t", ""), ("theta", "rad"), ("H", "mm"), ("G", "kPa"), ("u_r", "mm"), ("u_z", "mm"),
    ("B_r", "T"), ("B_z", "T"), ("F_r", "N"), ("F_z", "N"))}
#: Long names of the geometric design variables' dimensions (after ``DIMS``, in metres).
GEOMETRY_NAMES = {"R_m": "magnet radius", "H_m": "magnet height", "R": "body radius"}
BUNDLED_NAME = "magone_doe.nc"


def assemble(study: Study, field_job: FieldJob, field: Entry | None, path_jobs: list[PathJob],
             paths: dict[str, Entry], attrs: dict) -> xr.Dataset:
    """Build the data set from the job results (missing results are NaN).

    Forces of a path solved at ``G_0`` (``job.G is None``) are scaled to each G level:
    F(G) = F(G_0) · G / G_0 (exact for the incompressible neo-Hookean body with Coulomb friction
    under displacement control; docs/method.md §3).
    """
    t, theta, H, G = study.t_levels, study.theta_levels, study.H_levels, study.G_levels
    shape3 = (len(t), len(theta), len(H))
    data = {name: np.full(shape3 if len(dims) == 3 else shape3 + (len(G),), np.nan)
            for name, (dims, _, _) in VARIABLES.items()}
    if field is not None:
        data["B_r"][:], data["B_z"][:] = field.arrays["B_r"], field.arrays["B_z"]
    i_theta = {float(v): i for i, v in enumerate(theta)}
    i_H = {float(v): i for i, v in enumerate(H)}
    i_G = {float(v): i for i, v in enumerate(G)}
    for job in path_jobs:
        entry = paths.get(job.key)
        if entry is None:
            continue
        i, j = i_theta[job.theta], i_H[job.H]
        a = entry.arrays
        data["u_r"][:, i, j], data["u_z"][:, i, j] = a["u_r"], a["u_z"]
        if job.G is None:
            scale = G / float(entry.meta["G"])
            data["F_r"][:, i, j, :] = a["F_r"][:, None] * scale
            data["F_z"][:, i, j, :] = a["F_z"][:, None] * scale
        else:
            k = i_G[job.G]
            data["F_r"][:, i, j, k], data["F_z"][:, i, j, k] = a["F_r"], a["F_z"]
    ds = xr.Dataset(
        {name: (dims, data[name], {"units": u, "long_name": ln})
         for name, (dims, u, ln) in VARIABLES.items()},
        coords={name: (name, values, {"units": COORDS[name][0], "long_name": COORDS[name][1]})
                for name, values in zip(DIMS, (t, theta, H, G), strict=True)},
    )
    ds.attrs.update(provenance(study, field_job, field, path_jobs, paths))
    ds.attrs.update(attrs)
    return ds


def provenance(study: Study, field_job: FieldJob, field: Entry | None, path_jobs: list[PathJob],
               paths: dict[str, Entry]) -> dict:
    """Global attributes: study, versions, solvers, mesh sizes and per-job statistics."""
    jobs = []
    for job in path_jobs:
        entry = paths.get(job.key)
        rec = {"theta": job.theta, "H": job.H, "G": job.G, "key": job.key}
        if entry is not None:
            rec.update({k: entry.meta[k] for k in ("newton_iterations", "cutbacks", "n_dofs",
                                                   "n_cells", "mesh", "wall_time")})
            rec["G_solved"] = entry.meta["G"]
            rec["job_wall_time"] = entry.meta.get("job_wall_time")
            if "t_reached" in entry.meta:  # a failed path's levels up to there
                rec["t_reached"] = entry.meta["t_reached"]
        jobs.append(rec)
    meshes = sorted({r["mesh"] for r in jobs if r.get("mesh")})
    cells = [r["n_cells"] for r in jobs if "n_cells" in r]
    return {
        "title": f"magtact design of experiments: {study.name}",
        "study_name": study.name,
        "study_toml": study.to_toml(),
        "versions": json.dumps(versions(DOE), sort_keys=True),
        "created_utc": datetime.now(UTC).isoformat(timespec="seconds"),
        "field_solver": field_job.solver,
        "field_key": field_job.key,
        "field_wall_time_s": float(field.meta.get("job_wall_time", np.nan)) if field else np.nan,
        "mesh": ", ".join(meshes),
        "mesh_n_cells_min": int(min(cells)) if cells else -1,
        "mesh_n_cells_max": int(max(cells)) if cells else -1,
        "forces_scaled_in_G": int(study.mechanics.scale_in_G),
        "jobs": json.dumps(jobs),
        "jobs_doc": "JSON list, one record per structural path: theta [rad], H [m], G [Pa] or "
                    "null (solved at G_solved and scaled), cache key, newton_iterations, "
                    "cutbacks, n_dofs, n_cells, mesh, wall_time [s] of the solver, "
                    "job_wall_time [s] of the whole job",
    }


def save_dataset(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """Write ``ds`` to netCDF-4 (h5netcdf, compressed) atomically; return the path."""
    encoding = {name: {"zlib": True, "complevel": 4} for name in ds.data_vars}
    with atomic_path(path) as tmp:
        ds.to_netcdf(tmp, engine="h5netcdf", encoding=encoding)
    return Path(path)


def load_dataset(path: str | os.PathLike) -> xr.Dataset:
    """Read a DOE data set written by :func:`save_dataset` (fully into memory) and check it.

    Raises :class:`~magtact.MagtactError` if the file is missing or if it lacks a
    dimension or variable of the layout.
    """
    path = Path(path)
    problem = file_problem(path)
    if problem == "not found":
        raise MissingFileError(f"DOE data set not found: {path}")
    if problem is not None:
        raise MagtactError(f"{path}: not a DOE data set: it is {problem}")
    ds = _open_whole(path)
    for dim in DIMS:
        if dim not in ds.dims:
            raise MagtactError(f"{path}: not a DOE data set (no dimension {dim!r})")
    extra = geometry_dims(ds)
    for name, (dims, units, _) in VARIABLES.items():
        if name not in ds.data_vars:
            raise MagtactError(f"{path}: not a DOE data set (no variable {name!r})")
        dims = dims + extra
        if ds[name].dims != dims or ds[name].attrs.get("units") != units:
            raise MagtactError(f"{path}: variable {name!r} should have dims {dims} and units "
                               f"{units!r}, has {ds[name].dims} and "
                               f"{ds[name].attrs.get('units')!r}")
    return ds


#: HDF5 and netCDF-4 bookkeeping attributes, not the data set's own.
_H5_BOOKKEEPING = frozenset({"DIMENSION_LIST", "REFERENCE_LIST", "CLASS", "NAME",
                             "_Netcdf4Coordinates", "_Netcdf4Dimid", "_FillValue",
                             "_NCProperties", "_nc3_strict"})


#: Attributes by which CF conventions encode values (xarray decodes them on reading).
_CF_ENCODED = frozenset({"scale_factor", "add_offset", "missing_value", "dtype", "calendar",
                         "compress", "flag_values"})


def _attribute(value):
    """An HDF5 attribute's value as xarray gives it: text decoded, one-element arrays as
    their element."""
    if isinstance(value, bytes | np.bytes_):
        return value.decode()
    if isinstance(value, np.ndarray) and value.shape == (1,) and value.dtype.kind in "fiu":
        return value[0]
    return value


def _read_h5(path: Path) -> xr.Dataset | None:
    """The netCDF-4 file at ``path`` read through HDF5 directly, as :func:`save_dataset`
    writes it: flat, every variable a float array over dimension scales that carry their
    coordinates. None for any other layout (groups, dimensions without coordinates, other
    types), which xarray then reads. Opening through xarray's netCDF layers costs ten times
    more, and a design reads a data set for each magnet size it compares.

    The files xarray encodes otherwise (CF scale factors, fill values of integers, dates) are
    among those left to it."""
    import h5py
    import pandas as pd

    with h5py.File(path, "r") as f:
        items = dict(f.items())
        if any(not isinstance(v, h5py.Dataset) or v.dtype.kind not in "fi"
               or ("_FillValue" in v.attrs
                   and not (v.dtype.kind == "f" and np.isnan(v.attrs["_FillValue"]).all()))
               or not _CF_ENCODED.isdisjoint(v.attrs) for v in items.values()):
            return None
        scales = {}
        for name, v in items.items():
            if v.attrs.get("CLASS") == b"DIMENSION_SCALE":
                if v.ndim != 1 or "_Netcdf4Dimid" not in v.attrs:
                    return None
                scales[int(v.attrs["_Netcdf4Dimid"])] = name
        variables = {}
        for name, v in items.items():
            ids = v.attrs.get("_Netcdf4Coordinates")
            if ids is None or any(int(i) not in scales for i in ids) or len(ids) != v.ndim:
                return None
            attrs = {k: _attribute(a) for k, a in v.attrs.items() if k not in _H5_BOOKKEEPING}
            variables[name] = (tuple(scales[int(i)] for i in ids), v[()], attrs)
        attrs = {k: _attribute(a) for k, a in f.attrs.items() if k not in _H5_BOOKKEEPING}
    dims = [name for name in variables if name in scales.values()]  # in the file's order
    coords = {d: xr.Variable((d,), pd.Index(variables[d][1], name=d), variables[d][2])
              for d in dims}
    # plain arrays, as xarray's own reading leaves them (its checks of other array types
    # would import dask)
    data = {k: xr.Variable(*v, fastpath=True) for k, v in variables.items() if k not in dims}
    return xr.Dataset(data, coords=coords, attrs=attrs)


def _open_whole(path: Path) -> xr.Dataset:
    """The netCDF file at ``path`` read into memory, each dimension's coordinate indexed
    (:func:`_read_h5` where the file has save_dataset's layout).

    The indexes are made from the coordinates' values as pandas indexes (their attributes and
    encoding kept), not by xarray on opening: there it asks, of each coordinate, whether it is
    a dask array, which imports dask (a tenth of a second of a cold design)."""
    import inspect

    import pandas as pd

    try:
        direct = _read_h5(path)
    except (OSError, ValueError, KeyError):  # xarray's own reading says what is wrong
        direct = None
    if direct is not None:
        return direct
    if "create_default_indexes" not in inspect.signature(xr.open_dataset).parameters:
        with xr.open_dataset(path, engine="h5netcdf") as ds:  # an xarray without the argument
            return ds.load()
    with xr.open_dataset(path, engine="h5netcdf", create_default_indexes=False) as ds:
        ds = ds.load()
    dims = {d: ds[d] for d in ds.dims if d in ds.coords and ds[d].dims == (d,)}
    out = ds.assign_coords({d: pd.Index(v.values, name=d) for d, v in dims.items()})
    for d, v in dims.items():
        out[d].attrs, out[d].encoding = dict(v.attrs), dict(v.encoding)
    return out


def geometry_dims(ds: xr.Dataset) -> tuple[str, ...]:
    """The data set's dimensions of geometric design variables besides H (after ``DIMS``)."""
    return tuple(d for d in ds.dims if d in GEOMETRY_NAMES)


def bundled_path(name: str = BUNDLED_NAME) -> Path:
    """Location of a bundled data set (default: the MagOne study's) inside the installed
    package."""
    return Path(str(resources.files("magtact.doe").joinpath("data", name)))


def load_bundled(name: str = BUNDLED_NAME) -> xr.Dataset:
    """A DOE shipped with magtact (see ``magtact/doe/data/README.md``): by default the
    built-in MagOne study's, ``"broad_3x1_doe.nc"`` (and the other :data:`BROAD_SIZES`) the
    MagOne body with that magnet over H 2-10 mm."""
    path = bundled_path(name)
    if not path.is_file():
        raise FileNotFoundError(f"the bundled DOE data set is missing ({path}); rebuild it with "
                                "'python -m magtact.doe.bundle'")
    ds = load_dataset(path)
    ds.attrs["bundled_name"] = name  # what a rescaling of it names as its source
    return ds


def write_csv(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """Export ``ds`` as CSV, one row per (t, theta, H, G), G fastest; user units in the header.

    Columns: ``t,theta_rad,H_mm,G_kPa,u_r_mm,u_z_mm,B_r_T,B_z_T,F_r_N,F_z_N``; the geometric
    design variables besides H (``R_m_mm``, ...) follow ``G_kPa`` and vary fastest. Numbers are
    written in their shortest exact form (they read back to the same doubles).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    order = DIMS + geometry_dims(ds)

    def column(var: str, unit: str) -> np.ndarray:
        return from_si(ds[var].broadcast_like(ds["F_r"]).transpose(*order).values.ravel(), unit)

    extra = {_csv_column(k, "mm"): (k, "mm") for k in geometry_dims(ds)}  # after G's column
    names = list(CSV_COLUMNS)
    at = [var for var, _ in CSV_COLUMNS.values()].index("G") + 1
    columns = {n: (extra | CSV_COLUMNS)[n] for n in names[:at] + list(extra) + names[at:]}
    full = {name: column(var, unit) for name, (var, unit) in columns.items()}
    return _write_csv(path, list(columns),
                     zip(*(full[name].tolist() for name in columns), strict=True),
                     cell=lambda x: repr(x + 0.0))  # + 0.0: no '-0.0'; shortest exact form


#: Study sections that hold settings a DOE data set depends on. Only part of them determines its
#: FE forces and field (:data:`FORCE_SETTINGS`); the rest is answered from the data exactly.
DOE_SECTIONS = ("body", "magnet", "loading", "material", "design", "doe", "magnetics",
                "mechanics")
#: The settings that determine the FE forces and the field of a DOE, by section (``None``: every
#: setting of the section). Everything else is answered from a data set exactly: forces are
#: proportional to G (so G_ref, the G range and the silicone only relabel them), the field is
#: proportional to M_z (the grade), the DOE's levels only say how a new DOE would sample, and
#: the thread count and the sparse solver change the forces by round-off (docs/method.md §3, §7).
FORCE_SETTINGS = {
    "body": None,
    "magnet": ("R_m", "H_m", "placement"),
    "loading": None,
    "material": ("bulk_ratio",),
    "magnetics": None,
    "mechanics": None,
}
#: Settings of those sections that do not change the forces beyond round-off.
ROUND_OFF_SETTINGS = {"mechanics": ("threads", "solver")}
#: Bundled data sets, in the order they are tried (the first that describes a study serves it).
#: The broad data sets: the MagOne body over H 2-10 mm, one per magnet size (diameter x height
#: in mm) of the broad DOE, each answering that size only (bench/bench_broad.py).
BROAD_SIZES = ("3x1", "3x2", "3x3", "4x1", "4x2", "5x1", "6x1", "6x2", "6x3")
BUNDLED_NAMES = (BUNDLED_NAME, *(f"broad_{size}_doe.nc" for size in BROAD_SIZES))


def matches_study(ds, study) -> bool:
    """True if the data set describes ``study``: it agrees in every setting that determines the
    FE forces and field (:data:`FORCE_SETTINGS`) and covers the study's heights and geometric
    design ranges (:func:`differences`)."""
    return not differences(ds, study)


def data_study(ds):
    """The study a data set was computed for (from its ``study_toml`` attribute), or a string
    saying why there is none."""
    text = ds.attrs.get("computed_for_study_toml", ds.attrs.get("study_toml"))
    if text is None:
        return "its study (the data set records none)"
    return _study_of_toml(text)


@functools.lru_cache(maxsize=64)
def _study_of_toml(text: str):
    """:func:`data_study` of a data set's study text (the same text, the same study: a
    frozen value, read once per process)."""
    import tomllib

    from ..study import study_from_dict

    try:
        # only the sections a DOE depends on: settings added since the data set was written
        # (sensitivity, optimisation, ...) take their defaults
        given = tomllib.loads(text)
        data = {k: v for k, v in given.items() if k in DOE_SECTIONS}
        # geometric design variables need the exact field: keep the settings that say so
        for name, key in (("metamodel", "b_model"), ("sensitivity", "definition")):
            if key in given.get(name, {}):
                data[name] = {key: given[name][key]}
        return study_from_dict(data | {"base": "magone"})
    except Exception:  # a data set whose study no longer loads belongs to no study of today
        return "its study (the data set's study no longer loads)"


def differences(ds, study) -> list[str]:
    """What keeps the data set from describing ``study``, one entry per setting
    (``[section] key = value (the data set's: ...)``), the setting that needs new mechanics
    first: a setting of :data:`FORCE_SETTINGS` that differs, a height range or geometric
    design range that reaches outside the data's levels, a fixed magnet or body size outside
    the data's range; ``["its study ..."]`` if the data set records no study that loads today.
    Empty when the study is answered from the data (after :func:`rescaled_for`)."""
    from dataclasses import fields

    other = data_study(ds)
    if isinstance(other, str):
        return [other]
    geo = {d: (float(ds[d].values.min()), float(ds[d].values.max())) for d in geometry_dims(ds)}
    out = []
    for name, keys in FORCE_SETTINGS.items():
        if name == "magnetics" and other.metamodel.b_model == "exact":
            continue  # its answers take the exact field, not the FE field of the data
        mine, theirs = getattr(study, name), getattr(other, name)
        for f in fields(mine):
            if (keys is not None and f.name not in keys) or \
                    f.name in ROUND_OFF_SETTINGS.get(name, ()):
                continue
            if f.name in geo and name in ("magnet", "body"):
                continue  # a geometric dimension of the data: checked against its range below
            a, b = getattr(mine, f.name), getattr(theirs, f.name)
            if a != b:
                digits = next((d for d in range(6, 17) if _user(a, f, d) != _user(b, f, d)), 17)
                out.append(f"[{name}] {_key(f)} = {_user(a, f, digits)} (the data set's: "
                           f"{_user(b, f, digits)})")
    H = (float(ds["H"].values.min()), float(ds["H"].values.max()))
    if not _inside(study.design.H, H):
        out.append(f"[design] H_mm = {_mm_range(study.design.H)} reaches outside the data's "
                   f"heights {_mm_range(H)} mm")
    design = study.geometric_variables
    for k, section in (("R_m", "magnet"), ("H_m", "magnet"), ("R", "body")):
        if k in design:
            if k not in geo or not _inside(design[k], geo[k]):
                span = (f"the data's range {_mm_range(geo[k])} mm" if k in geo
                        else "data in which it is fixed")
                out.append(f"[design] {k}_mm = {_mm_range(design[k])}: a design variable "
                           f"outside {span}")
        elif k in geo:
            v = getattr(getattr(study, section), k)
            if not _inside((v, v), geo[k]):
                out.append(f"[{section}] {k}_mm = {from_si(v, 'mm'):.6g} outside the data's "
                           f"range {_mm_range(geo[k])} mm")
    return out


def _key(f) -> str:
    unit = f.metadata.get("unit", "")
    return f"{f.name}_{unit}" if unit else f.name


def _inside(rng, span, rtol: float = 1e-9) -> bool:
    tol = rtol * max(abs(span[0]), abs(span[1]), 1e-300)
    return span[0] - tol <= rng[0] and rng[1] <= span[1] + tol


def _mm_range(rng) -> str:
    return f"[{from_si(rng[0], 'mm'):.6g}, {from_si(rng[1], 'mm'):.6g}]"


def _user(value, f, digits: int = 6):
    """``value`` of the setting ``f`` in its user unit, to ``digits`` significant figures."""
    unit = f.metadata.get("unit", "")
    if not unit or isinstance(value, (str, bool)):
        return repr(value)
    if isinstance(value, tuple):
        return "[" + ", ".join(f"{from_si(v, unit):.{digits}g}" for v in value) + "]"
    return f"{from_si(value, unit):.{digits}g}"


def rescaled_for(ds, study) -> xr.Dataset:
    """The data set relabelled exactly for ``study`` (which it must describe, :func:`differences`):
    the G levels become the study's, each force scaled by G / G_data (forces are proportional
    to G), and B scaled by M_z / M_z,data (the field is proportional to the magnetisation).

    The attributes keep the study the data were computed for (``computed_for_study_toml``),
    record the rescaling (``rescaled_from``, ``field_scale``, ``G_scaled_from_Pa``) and hold
    ``study`` as ``study_toml``. Returns ``ds`` itself when nothing changes.
    """
    other = data_study(ds)
    if isinstance(other, str):
        raise MagtactError(f"the data set cannot be rescaled: {other}")
    G_old = np.asarray(ds["G"].values, dtype=float)
    G_new = np.asarray(study.G_levels, dtype=float)
    k = study.magnet.M_z / other.magnet.M_z
    if k == 1.0 and G_old.shape == G_new.shape and np.array_equal(G_old, G_new):
        return ds
    # forces per unit G from the first level (forces are exactly proportional to G)
    out = ds.isel(G=[0] * len(G_new)).assign_coords(G=("G", G_new, dict(ds["G"].attrs)))
    for name in ("F_r", "F_z"):
        scale = xr.DataArray(G_new / G_old[0], dims="G", coords={"G": G_new})
        out[name] = (out[name] * scale).transpose(*ds[name].dims).assign_attrs(ds[name].attrs)
    for name in ("B_r", "B_z"):
        out[name] = (ds[name] * k).assign_attrs(ds[name].attrs)
    out.attrs = dict(ds.attrs)
    out.attrs.setdefault("computed_for_study_toml", ds.attrs.get("study_toml", ""))
    out.attrs.update({
        "study_toml": study.to_toml(),
        "rescaled_from": ds.attrs.get("rescaled_from", ds.attrs.get("bundled_name", "")),
        "field_scale": float(k) * float(ds.attrs.get("field_scale", 1.0)),
        "G_scaled_from_Pa": json.dumps(G_old.tolist()),
        "rescaling": "forces scaled exactly to the study's G levels (F proportional to G), B "
                     "by the study's M_z over the data's (B proportional to M_z)",
    })
    return out


def _holds(ds) -> str:
    """What a data set describes, in words: its magnet and heights ("" if its study does not
    load)."""
    other = data_study(ds)
    if isinstance(other, str):
        return ""
    m, H = other.magnet, ds["H"].values
    return (f"a {from_si(2 * m.R_m, 'mm'):.3g} × {from_si(m.H_m, 'mm'):.3g} mm magnet over H "
            f"{_mm_range((float(H.min()), float(H.max())))} mm")


def _outline(name: str) -> xr.Dataset:
    """A bundled data set's coordinates and attributes, what :func:`differences` and
    :func:`_holds` read, its arrays left unread (only the data set that describes a study is
    read whole). Read once per process while the file stays the same (a design asks for
    every magnet size's)."""
    path = bundled_path(name)
    if not path.is_file():
        return load_bundled(name)  # its error names the missing file
    stat = path.stat()
    key = (str(path), stat.st_mtime_ns, stat.st_size)
    if key not in _OUTLINES:
        _OUTLINES[key] = _read_outline(path)
    return _OUTLINES[key].copy()


#: The outlines read in this process, by (path, modification time, size).
_OUTLINES: dict[tuple, xr.Dataset] = {}


def _read_outline(path: Path) -> xr.Dataset:
    import h5py  # the netCDF-4 file's HDF5 layer: opening it through xarray costs 20 times more
    import pandas as pd

    with h5py.File(path, "r") as f:
        coords = {k: f[k][()] for k in (*DIMS, *GEOMETRY_NAMES) if k in f}
        attrs = {k: _attribute(v) for k, v in f.attrs.items() if k not in _H5_BOOKKEEPING}
    # each dimension's levels as a pandas index: xarray takes it as it is, where an array would
    # have it look for (and import) dask to tell what kind of array it was given
    coords = {k: pd.Index(v, name=k) if np.ndim(v) == 1 else v for k, v in coords.items()}
    return xr.Dataset(coords=coords, attrs=attrs)


def bundled_for(study, advice: str | None = None):
    """The bundled data set that describes ``study`` (:func:`differences`), rescaled exactly to
    its G levels and magnetisation (:func:`rescaled_for`): the MagOne data set, else the broad
    one over (H, R_m, H_m) where shipped.

    ``advice`` ends the error message: what to run instead, in terms of the caller's options
    (default: compute the study's own DOE and models, and give the models with ``--models``).

    Raises
    ------
    MagtactError
        Naming the setting that needs new mechanics (and any others) and what to run instead.
    """
    closest, held = None, []
    for name in BUNDLED_NAMES:
        path = bundled_path(name)
        if not path.is_file() and name != BUNDLED_NAME:
            continue
        ds = _outline(name)
        diff = differences(ds, study)
        if not diff:
            return rescaled_for(load_bundled(name), study)
        if closest is None or len(diff) < len(closest[1]):  # the data set nearest the study
            closest = (name, diff)
        held.append(ds)
    held = [_holds(ds) for ds in held]
    name, diff = closest
    shown = "; ".join(diff[1:6]) + (f"; and {len(diff) - 6} more" if len(diff) > 6 else "")
    raise MagtactError(
        f"study {study.name!r} needs new mechanics: {diff[0]}"
        + (f" (it also differs in {shown})" if shown else "")
        + ". No data set bundled with magtact describes it: they hold "
        + "; ".join(h for h in held if h)
        + " (what they answer: the same body, magnet size and placement, loading, bulk ratio and "
          "solvers, heights inside their range; G, the silicone, the grade and M_z, the chip "
          "and everything else are exact rescalings). "
        + (advice or "Compute its own DOE and models (magtact run STUDY --recompute; or "
                     "magtact doe STUDY --out DOE, then magtact fit STUDY --data DOE/doe.nc "
                     "--out MODELS, and give --models MODELS)"))
