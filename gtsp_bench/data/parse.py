"""Parsing and formatting of instance and solution text, kept apart from file I/O.

Two instance formats:

* JSON (UAV instances)::

    {"name": "...", "depot": [x, y] or null, "clusters": [[[x, y], ...], ...],
     "params": {"<energy parameter>": value, ...},   # optional overrides
     "meta": {...}}                                  # optional, free

* GTSPLIB ``.gtsp``: TSPLIB95 plus ``TYPE : GTSP``, ``GTSP_SETS : M`` and a ``GTSP_SET_SECTION``
  of ``set_id node node ... -1`` records. Coordinate types EUC_2D, CEIL_2D, ATT, GEO, GEOM, and
  EXPLICIT weights in any TSPLIB95 ``EDGE_WEIGHT_FORMAT`` (FULL_MATRIX, UPPER_ROW, LOWER_ROW,
  UPPER_DIAG_ROW, LOWER_DIAG_ROW and the ``_COL`` forms). ``TYPE : AGTSP`` (asymmetric) files
  give a FULL_MATRIX whose row i, column j is the cost of going from node i to node j; they
  become an instance with ``symmetric=False``.

And TSPLIB tour files (``TOUR_SECTION`` of 1-based node ids, ``-1`` at the end), the form in which
GTSPLIB's best tours are given: :func:`parse_tour`, then :func:`tour_to_solution`; written by
:func:`format_tour`, with node ids as :func:`tour_node_ids` defines them (a UAV instance's too).

Every function raises :class:`~gtsp_bench.errors.InputError` with a message that names the
problem; the I/O layer prefixes the file name.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np

from gtsp_bench.checks import MAX_TOUR_COST, check_finite_array, check_instance_numbers, is_int, is_number
from gtsp_bench.errors import InputError
from gtsp_bench.instance import Instance
from gtsp_bench.params import EnergyParams

_JSON_KEYS = {"name", "depot", "clusters", "params", "meta"}


# ---------------------------------------------------------------------- JSON instances
def _strict_json(text: str) -> Any:
    def reject(token: str) -> None:
        raise InputError(f"invalid JSON: {token} is not a number")

    try:
        return json.loads(text, parse_constant=reject)
    except json.JSONDecodeError as e:
        raise InputError(f"invalid JSON: {e.msg} at line {e.lineno} column {e.colno}") from None
    except InputError:
        raise
    except (ValueError, RecursionError) as e:  # an integer of > 4300 digits, absurd nesting
        raise InputError(f"invalid JSON: {str(e).split(':')[0]}") from None


def _point(value: Any, where: str) -> list[float]:
    if (
        not isinstance(value, list)
        or len(value) != 2
        or not all(is_number(v) for v in value)
    ):
        raise InputError(f"{where} must be a pair of numbers [x, y], got {value!r}")
    try:
        point = [float(v) for v in value]
    except OverflowError:  # an integer literal too large for a float
        point = [math.inf]
    if not all(math.isfinite(v) for v in point):
        raise InputError(f"{where} has a NaN or infinite coordinate")
    return point


def instance_from_dict(data: Any, default_name: str = "instance") -> Instance:
    """Build a UAV instance from the decoded JSON object.

    Parameters
    ----------
    data
        The decoded JSON value.
    default_name
        Name used when the object has none.
    """
    if not isinstance(data, dict):
        raise InputError("an instance must be a JSON object")
    unknown = sorted(set(data) - _JSON_KEYS)
    if unknown:
        raise InputError(f"unknown key {unknown[0]!r} (valid: {', '.join(sorted(_JSON_KEYS))})")
    if "clusters" not in data:
        raise InputError("missing key 'clusters'")
    name = data.get("name", default_name)
    if not isinstance(name, str) or not name:
        raise InputError("'name' must be a non-empty string")
    clusters_raw = data["clusters"]
    if not isinstance(clusters_raw, list) or not clusters_raw:
        raise InputError("'clusters' must be a non-empty list of clusters")
    clusters = []
    for k, cluster in enumerate(clusters_raw):
        if not isinstance(cluster, list):
            raise InputError(f"clusters[{k}] must be a list of [x, y] points")
        if not cluster:
            raise InputError(f"clusters[{k}] is empty")
        clusters.append(np.array([_point(p, f"clusters[{k}][{i}]") for i, p in enumerate(cluster)]))
    depot_raw = data.get("depot")
    depot = None if depot_raw is None else np.array(_point(depot_raw, "depot"))
    params_raw = data.get("params") or {}
    if not isinstance(params_raw, dict):
        raise InputError("'params' must be an object of energy parameter overrides")
    params = EnergyParams.from_mapping(params_raw)
    meta = data.get("meta") or {}
    if not isinstance(meta, dict):
        raise InputError("'meta' must be an object")
    instance = Instance(name=name, clusters=tuple(clusters), depot=depot, params=params, meta=meta)
    check_instance_numbers(instance)
    return instance


def parse_json_instance(text: str, default_name: str = "instance") -> Instance:
    """Parse the JSON text of a UAV instance."""
    return instance_from_dict(_strict_json(text), default_name)


def parse_instance_text(text: str, default_name: str = "instance") -> Instance:
    """Parse the text of an instance file of either format: a JSON object (UAV) when its first
    non-blank character is ``{``, else GTSPLIB (:func:`parse_gtsp`)."""
    if text.lstrip().startswith("{"):
        return parse_json_instance(text, default_name)
    return parse_gtsp(text)


def instance_to_dict(instance: Instance) -> dict[str, Any]:
    """The JSON object of a UAV instance (energy parameters: only the overrides)."""
    if instance.params is None:
        raise InputError(f"{instance.name} is a distance-only instance; write it as .gtsp")
    out: dict[str, Any] = {
        "name": instance.name,
        "depot": None if instance.depot is None else instance.depot.tolist(),
        "clusters": [c.tolist() for c in instance.clusters],
    }
    if overrides := instance.params.overrides():
        out["params"] = overrides
    if instance.meta:
        out["meta"] = dict(instance.meta)
    return out


def format_json_instance(instance: Instance) -> str:
    """JSON text of a UAV instance (one cluster per line, readable and compact)."""
    d = instance_to_dict(instance)
    lines = ["{", f'  "name": {json.dumps(d["name"])},', f'  "depot": {json.dumps(d["depot"])},']
    lines.append('  "clusters": [')
    lines.append(",\n".join(f"    {json.dumps(c)}" for c in d["clusters"]))
    tail = [f'  "{key}": {json.dumps(d[key], sort_keys=True)}' for key in ("params", "meta") if key in d]
    lines.append("  ]" + ("," if tail else ""))
    lines.append(",\n".join(tail))
    lines.append("}")
    return "\n".join(line for line in lines if line) + "\n"


# ---------------------------------------------------------------------- solutions
def parse_solution(text: str) -> tuple[list[int], list[int]]:
    """Read ``order`` and ``heads`` from a solution JSON object (other keys are ignored)."""
    data = _strict_json(text)
    if not isinstance(data, dict):
        raise InputError("a solution must be a JSON object with 'order' and 'heads'")
    out = []
    for key in ("order", "heads"):
        if key not in data:
            raise InputError(f"missing key {key!r}")
        value = data[key]
        if not isinstance(value, list) or not all(is_int(v) for v in value):
            raise InputError(f"{key!r} must be a list of integers")
        out.append(value)
    return out[0], out[1]


# ---------------------------------------------------------------------- GTSPLIB
_SECTIONS = {"NODE_COORD_SECTION", "GTSP_SET_SECTION", "EDGE_WEIGHT_SECTION",
             "DISPLAY_DATA_SECTION", "TOUR_SECTION", "EOF"}
#: Header keys also accepted without a colon (``TYPE  AGTSP`` occurs in GTSPLIB).
_HEADER_KEYS = {"NAME", "TYPE", "COMMENT", "DIMENSION", "GTSP_SETS", "EDGE_WEIGHT_TYPE",
                "EDGE_WEIGHT_FORMAT", "NODE_COORD_TYPE", "DISPLAY_DATA_TYPE"}
_NUMBER_START = frozenset("0123456789-+.")
_COORD_TYPES = {"EUC_2D", "CEIL_2D", "ATT", "GEO", "GEOM"}
#: EDGE_WEIGHT_FORMAT of a symmetric matrix given by one triangle: the triangle in row-major
#: order, and whether the diagonal is included. A ``_COL`` form lists the other triangle row by
#: row, the same entries of a symmetric matrix in the same order.
_TRIANGLES = {
    "UPPER_ROW": ("upper", False), "LOWER_COL": ("upper", False),
    "LOWER_ROW": ("lower", False), "UPPER_COL": ("lower", False),
    "UPPER_DIAG_ROW": ("upper", True), "LOWER_DIAG_COL": ("upper", True),
    "LOWER_DIAG_ROW": ("lower", True), "UPPER_DIAG_COL": ("lower", True),
}
_WEIGHT_FORMATS = ("FULL_MATRIX", *_TRIANGLES)


def _split_key(line: str) -> tuple[str, str]:
    if ":" in line:
        key, value = line.split(":", 1)
        return key.strip().upper(), value.strip()
    parts = line.split(None, 1)
    if len(parts) == 2 and parts[0].upper() in _HEADER_KEYS:
        return parts[0].upper(), parts[1].strip()
    return line.strip().upper(), ""


def _tsplib_sections(text: str) -> tuple[dict[str, str], dict[str, list[str]]]:
    """Split TSPLIB text into its header (``KEY: value``) and its sections' lines (to ``EOF``)."""
    header: dict[str, str] = {}
    sections: dict[str, list[str]] = {}
    current: str | None = None
    for raw in text.splitlines():
        line = raw.strip()
        if not line:
            continue
        if current is not None and line[0] in _NUMBER_START:  # a data line: no key to look for
            sections[current].append(line)
            continue
        key, value = _split_key(line)
        if key in _SECTIONS:
            if key == "EOF":
                break
            current = key
            sections[current] = [value] if value else []
        elif current is None:
            header[key] = value
        else:
            sections[current].append(line)
    return header, sections


def parse_gtsp(text: str) -> Instance:
    """Parse a GTSPLIB ``.gtsp`` text into a distance-only :class:`Instance`.

    Clusters keep the file's set order; the nodes of a set keep the order in which the set lists
    them. ``meta`` records the name, comment and original node ids. Explicit weights in any
    triangle format become the full matrix; the diagonal is ignored (TSPLIB95; some files put a
    large number there) and stored as 0. An ``AGTSP`` file (its FULL_MATRIX may be asymmetric:
    row = from, column = to) gives an instance with ``symmetric=False``; a symmetric type whose
    FULL_MATRIX is not symmetric is an error.
    """
    header, sections = _tsplib_sections(text)
    # The first word: "TYPE : GTSP (M.~Hofmeister)" occurs.
    gtsp_type = (header.get("TYPE", "").split() or [""])[0].upper()
    if gtsp_type not in {"GTSP", "AGTSP"} and "GTSP_SETS" not in header:
        raise InputError("not a GTSP file (TYPE is not GTSP and there is no GTSP_SETS)")
    symmetric = gtsp_type != "AGTSP"
    ewt = header.get("EDGE_WEIGHT_TYPE", "").upper()
    if ewt not in _COORD_TYPES | {"EXPLICIT"}:
        raise InputError(
            f"unsupported EDGE_WEIGHT_TYPE {ewt or '(missing)'!r} "
            f"(supported: {', '.join(sorted(_COORD_TYPES | {'EXPLICIT'}))})"
        )
    dim = _header_int(header, "DIMENSION")
    n_sets = _header_int(header, "GTSP_SETS")
    coord_lines = sections.get("NODE_COORD_SECTION") or sections.get("DISPLAY_DATA_SECTION")
    coords = _parse_coords(coord_lines, dim, ewt)
    sets = _parse_sets(sections.get("GTSP_SET_SECTION"), dim, n_sets)
    weights = None
    if ewt == "EXPLICIT":
        weights = _parse_weights(header, sections.get("EDGE_WEIGHT_SECTION"), dim, symmetric)
    elif not symmetric:
        raise InputError(f"an asymmetric (AGTSP) file needs EXPLICIT weights, not {ewt}")
    order = np.concatenate(sets)  # original (0-based) node ids in cluster order
    if coords is None:
        coords = np.full((dim, 2), np.nan)
    clusters = tuple(np.split(coords[order], np.cumsum([len(s) for s in sets])[:-1]))
    name = header.get("NAME", "gtsp")
    meta = {"format": "gtsplib", "node_ids": (order + 1).tolist()}
    if header.get("COMMENT"):
        meta["comment"] = header["COMMENT"]
    instance = Instance(
        name=name,
        clusters=clusters,
        depot=None,
        params=None,
        edge_weight_type=ewt,
        weights=None if weights is None else weights[np.ix_(order, order)],
        meta=meta,
        symmetric=symmetric,
    )
    check_instance_numbers(instance)
    return instance


def _header_int(header: Mapping[str, str], key: str) -> int:
    if key not in header:
        raise InputError(f"missing {key}")
    try:
        value = int(header[key])
    except ValueError:
        raise InputError(f"{key} must be an integer, got {header[key]!r}") from None
    if value < 1:
        raise InputError(f"{key} must be >= 1, got {value}")
    return value


def _parse_coords(lines: list[str] | None, dim: int, ewt: str) -> np.ndarray | None:
    if lines is None:
        if ewt == "EXPLICIT":
            return None
        raise InputError("missing NODE_COORD_SECTION")
    fast = _coords_fast(lines, dim)
    if fast is not None:
        return fast
    points: dict[int, tuple[float, float]] = {}
    for line in lines:
        parts = line.split()
        try:
            node, x, y = int(parts[0]), float(parts[1]), float(parts[2])
        except (ValueError, IndexError):
            raise InputError(f"bad coordinate line {line!r}") from None
        if not 1 <= node <= dim:
            raise InputError(f"node {node} is outside 1..{dim} (DIMENSION)")
        if node in points:
            raise InputError(f"node {node} has two coordinate lines")
        if not (math.isfinite(x) and math.isfinite(y)):
            raise InputError(f"node {node} has a NaN or infinite coordinate")
        points[node] = (x, y)
    if len(points) < dim:  # checked before allocating: DIMENSION may be far too large
        raise InputError(f"node {_first_missing(points)} has no coordinates")
    coords = np.empty((dim, 2))
    coords[np.fromiter(points, dtype=np.int64, count=dim) - 1] = list(points.values())
    return coords


def _coords_fast(lines: list[str], dim: int) -> np.ndarray | None:
    """The coordinates of well-formed lines ``node x y`` (each node 1..dim once, finite values),
    vectorised; ``None`` for anything else, which the line-by-line reader then names."""
    tokens = " ".join(lines).split()
    if len(lines) != dim or len(tokens) != 3 * dim:
        return None
    try:
        table = np.array(tokens, dtype=np.float64).reshape(dim, 3)
    except ValueError:
        return None
    ids = table[:, 0]
    if not (np.all(np.isfinite(table)) and np.all(ids == np.round(ids))):  # inf ids: no cast
        return None
    nodes = ids.astype(np.int64)
    if nodes.min() < 1 or nodes.max() > dim or np.bincount(nodes).max() > 1:
        return None
    coords = np.empty((dim, 2))
    coords[nodes - 1] = table[:, 1:]
    return coords


def _first_missing(present: Iterable[int]) -> int:
    """The smallest id >= 1 that is not in ``present``."""
    ids = sorted(present)
    for expected, node in enumerate(ids, start=1):
        if node != expected:
            return expected
    return len(ids) + 1


def _parse_sets(lines: list[str] | None, dim: int, n_sets: int) -> list[np.ndarray]:
    if lines is None:
        raise InputError("missing GTSP_SET_SECTION")
    fast = _sets_fast(lines, dim, n_sets)
    if fast is not None:
        return fast
    tokens: list[int] = []
    for line in lines:
        try:
            tokens.extend(int(t) for t in line.split())
        except ValueError:
            raise InputError(f"bad set line {line!r}") from None
    sets: dict[int, list[int]] = {}
    owner: dict[int, int] = {}  # node (0-based) -> set id; a dict: DIMENSION may be far too large
    i = 0
    while i < len(tokens):
        set_id = tokens[i]
        if set_id in sets:
            raise InputError(f"set {set_id} is listed twice")
        members = []
        i += 1
        while i < len(tokens) and tokens[i] != -1:
            node = tokens[i]
            if not 1 <= node <= dim:
                raise InputError(f"set {set_id} names node {node}, outside 1..{dim}")
            if node - 1 in owner:
                raise InputError(f"node {node} is in set {owner[node - 1]} and in set {set_id}")
            owner[node - 1] = set_id
            members.append(node - 1)
            i += 1
        if i == len(tokens):
            raise InputError(f"set {set_id} is not terminated by -1")
        i += 1
        if not members:
            raise InputError(f"set {set_id} is empty")
        sets[set_id] = members
    if len(sets) != n_sets:
        raise InputError(f"GTSP_SETS says {n_sets} sets but GTSP_SET_SECTION has {len(sets)}")
    if len(owner) < dim:
        raise InputError(f"node {_first_missing(n + 1 for n in owner)} is in no set")
    return [np.array(sets[s]) for s in sorted(sets)]


def _sets_fast(lines: list[str], dim: int, n_sets: int) -> list[np.ndarray] | None:
    """The sets of a well-formed GTSP_SET_SECTION (``n_sets`` records ``id node ... -1`` with
    distinct ids, every node 1..dim in exactly one), vectorised and by set id; ``None`` for
    anything else, which the record-by-record reader then names."""
    try:
        tokens = np.array(" ".join(lines).split(), dtype=np.int64)
    except (ValueError, OverflowError):
        return None
    ends = np.flatnonzero(tokens == -1)
    if len(ends) != n_sets or len(tokens) == 0 or ends[-1] != len(tokens) - 1:
        return None
    starts = np.concatenate([[0], ends[:-1] + 1])
    ids = tokens[starts]
    is_member = np.ones(len(tokens), dtype=bool)
    is_member[starts] = False
    is_member[ends] = False
    members = tokens[is_member]
    if (np.any(ends - starts < 2) or len(members) != dim or members.min() < 1
            or members.max() > dim or np.bincount(members).max() > 1
            or len(set(ids.tolist())) != n_sets):
        return None
    by_id = np.argsort(ids, kind="stable")
    return [tokens[starts[i] + 1:ends[i]] - 1 for i in by_id]


def _parse_weights(header: Mapping[str, str], lines: list[str] | None, dim: int,
                   symmetric: bool = True) -> np.ndarray:
    """The full ``(dim, dim)`` matrix of an EDGE_WEIGHT_SECTION, zero diagonal; row = from,
    column = to. Only a FULL_MATRIX can be asymmetric, and only when ``symmetric`` is false."""
    fmt = header.get("EDGE_WEIGHT_FORMAT", "").upper()
    if fmt not in _WEIGHT_FORMATS:
        raise InputError(f"unsupported EDGE_WEIGHT_FORMAT {fmt or '(missing)'!r} "
                         f"(supported: {', '.join(_WEIGHT_FORMATS)})")
    if not symmetric and fmt != "FULL_MATRIX":
        raise InputError(f"an asymmetric (AGTSP) file needs EDGE_WEIGHT_FORMAT FULL_MATRIX, not {fmt}")
    if lines is None:
        raise InputError("missing EDGE_WEIGHT_SECTION")
    try:
        values = np.array(" ".join(lines).split(), dtype=np.float64)
    except ValueError:
        raise InputError("EDGE_WEIGHT_SECTION has a value that is not a number") from None
    if fmt == "FULL_MATRIX":
        needed = dim * dim
    else:
        triangle, diagonal = _TRIANGLES[fmt]
        needed = dim * (dim + 1) // 2 if diagonal else dim * (dim - 1) // 2
    if values.size != needed:
        raise InputError(f"EDGE_WEIGHT_SECTION has {values.size} values, {fmt} needs {needed}")
    if fmt == "FULL_MATRIX":
        w = values.reshape(dim, dim).copy()
    else:
        w = np.zeros((dim, dim))
        offset = 0 if diagonal else 1
        rows, cols = np.triu_indices(dim, offset) if triangle == "upper" else np.tril_indices(dim, -offset)
        w[rows, cols] = values
        w[cols, rows] = values
    np.fill_diagonal(w, 0.0)
    check_finite_array("EDGE_WEIGHT_SECTION", w, MAX_TOUR_COST)  # before symmetry: nan != nan
    if symmetric and fmt == "FULL_MATRIX" and not np.array_equal(w, w.T):  # a triangle is symmetric
        i, j = (int(v) for v in np.argwhere(w != w.T)[0])
        raise InputError(f"EDGE_WEIGHT_SECTION is not symmetric (node {i + 1} to {j + 1} weighs "
                         f"{w[i, j]:g}, back {w[j, i]:g}); an asymmetric file says TYPE : AGTSP")
    return w


def format_gtsp(instance: Instance) -> str:
    """GTSPLIB text of a distance-only instance; nodes are numbered 1..n in cluster order."""
    if instance.params is not None:
        raise InputError(f"{instance.name} is a UAV instance; write it as .json")
    ewt = instance.edge_weight_type
    lines = [f"NAME : {instance.name}", f"TYPE : {'GTSP' if instance.symmetric else 'AGTSP'}"]
    if instance.meta.get("comment"):
        lines.append(f"COMMENT : {instance.meta['comment']}")
    lines += [f"DIMENSION : {instance.n_nodes}", f"GTSP_SETS : {instance.n_clusters}",
              f"EDGE_WEIGHT_TYPE : {ewt}"]
    if ewt == "EXPLICIT":
        lines += ["EDGE_WEIGHT_FORMAT : FULL_MATRIX", "EDGE_WEIGHT_SECTION"]
        lines += [" ".join(repr(float(v)) for v in row) for row in instance.weights]
    coords = instance.coords
    if np.all(np.isfinite(coords)):
        lines.append("NODE_COORD_SECTION" if ewt != "EXPLICIT" else "DISPLAY_DATA_SECTION")
        lines += [f"{i + 1} {x!r} {y!r}" for i, (x, y) in enumerate(coords.tolist())]
    lines.append("GTSP_SET_SECTION")
    for k, (offset, size) in enumerate(zip(instance.offsets, instance.sizes, strict=True)):
        nodes = " ".join(str(v) for v in range(offset + 1, offset + size + 1))
        lines.append(f"{k + 1} {nodes} -1")
    lines.append("EOF")
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------- TSPLIB tours
def parse_tour(text: str) -> list[int]:
    """The node ids of a TSPLIB tour file's ``TOUR_SECTION`` (1-based, as in the instance file).

    The section ends at ``-1`` (or at ``EOF``); a tour file with ``DIMENSION`` must list that many
    nodes. GTSPLIB's best tours list one node of each cluster in visiting order.
    """
    header, sections = _tsplib_sections(text)
    lines = sections.get("TOUR_SECTION")
    if lines is None:
        raise InputError("missing TOUR_SECTION")
    nodes: list[int] = []
    for token in " ".join(lines).split():
        try:
            node = int(token)
        except ValueError:
            raise InputError(f"TOUR_SECTION has {token!r}, not a node id") from None
        if node == -1:
            break
        if node < 1:
            raise InputError(f"TOUR_SECTION has node {node}; node ids start at 1")
        nodes.append(node)
    if not nodes:
        raise InputError("TOUR_SECTION is empty")
    if "DIMENSION" in header and len(nodes) != _header_int(header, "DIMENSION"):
        raise InputError(f"DIMENSION says {header['DIMENSION']} nodes but TOUR_SECTION has {len(nodes)}")
    return nodes


def tour_node_ids(instance: Instance) -> np.ndarray:
    """The node id that names each node (in global order) in a tour file: ``(n,)``, 1-based.

    For an instance read from a GTSPLIB file these are the file's node ids (``meta["node_ids"]``);
    for any other instance, a UAV instance included, node ``offsets[k] + i + 1`` is node ``i`` of
    cluster ``k``: the nodes numbered 1..n in cluster order, as in the JSON file (and as
    :func:`format_gtsp` numbers them). The depot is never in a tour file.
    """
    file_ids = None if instance.is_uav else instance.meta.get("node_ids")
    if file_ids is None:
        return np.arange(1, instance.n_nodes + 1)
    ids = np.asarray(file_ids, dtype=np.int64)
    if ids.shape != (instance.n_nodes,) or len(np.unique(ids)) != len(ids):
        raise InputError(f"{instance.name}: its node ids (meta['node_ids']) do not match its "
                         f"{instance.n_nodes} nodes")
    return ids


def format_tour(instance: Instance, order: Sequence[int], heads: Sequence[int],
                comments: Sequence[str] = ()) -> str:
    """TSPLIB tour text (the form of GLKH's tours) of a solution: its heads' node ids in visiting
    order, one per cluster (:func:`tour_node_ids`; a UAV tour starts and ends at the depot,
    which is not listed).

    Raises
    ------
    InfeasibleSolutionError
        For a solution that is not one of ``instance`` (:meth:`Instance.check_solution`).
    """
    order_arr, heads_arr = instance.check_solution(order, heads)
    ids = tour_node_ids(instance)[instance.offsets[order_arr] + heads_arr[order_arr]]
    lines = [f"NAME : {instance.name}.tour"]
    lines += [f"COMMENT : {' '.join(c.split())}" for c in comments]
    lines += ["TYPE : TOUR", f"DIMENSION : {len(ids)}", "TOUR_SECTION"]
    lines += [str(v) for v in ids.tolist()]
    lines += ["-1", "EOF"]
    return "\n".join(lines) + "\n"


def tour_to_solution(instance: Instance, node_ids: Sequence[int]) -> tuple[list[int], list[int]]:
    """Turn a tour's node ids (1-based, :func:`tour_node_ids`) into ``(order, heads)``.

    Parameters
    ----------
    instance
        The instance the tour is of (for a GTSPLIB file: the one read from that file, whose
        ``meta["node_ids"]`` maps its nodes to the file's).
    node_ids
        One node of each cluster, in visiting order.

    Raises
    ------
    InputError
        For a tour that names a node the instance does not have, or lists more or fewer nodes
        than it has clusters (both: a tour of another instance, most likely). A tour that
        misses or repeats a cluster is left to :meth:`Instance.check_solution`.
    """
    ids = tour_node_ids(instance)
    position = {int(v): i for i, v in enumerate(ids.tolist())}
    for v in node_ids:
        if v not in position:
            raise InputError(f"tour names node {v}, which is not in {instance.name} "
                             f"(its nodes are {int(ids.min())}..{int(ids.max())})")
    k = instance.n_clusters
    if len(node_ids) != k:
        raise InputError(f"the tour lists {len(node_ids)} nodes, but a tour of {instance.name} lists "
                         f"one node of each of its {k} clusters")
    order: list[int] = []
    heads = [-1] * k
    for v in node_ids:
        node = position[v]
        c = int(instance.cluster_of[node])
        order.append(c)
        heads[c] = node - int(instance.offsets[c])
    return order, heads
