"""Sampling shared by joint and task-space trajectories: the rest-to-rest quintic profile and the reading
of CSV tables (:mod:`mcdm_pin.trajectory`, :mod:`mcdm_pin.ik.samples`)."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from .exceptions import TrajectoryError
from .limits import MAX_CSV_BYTES, MAX_SAMPLES


def quintic_profile(t: np.ndarray, duration: float):
    """s, ds/dt, d2s/dt2 of the rest-to-rest quintic on [0, duration]."""
    tau = np.clip(t / duration, 0.0, 1.0)
    s = tau**3 * (10 - 15 * tau + 6 * tau**2)
    ds = 30 * tau**2 * (1 - tau) ** 2 / duration
    dds = 60 * tau * (1 - tau) * (1 - 2 * tau) / duration**2
    return s, ds, dds


def csv_rows(path: Path) -> list[list[str]]:
    """The non-blank rows of the CSV file ``path`` (within docs/limits.md's size and row limits), or a
    :class:`~mcdm_pin.exceptions.TrajectoryError` naming the file."""
    try:
        size = path.stat().st_size
        if size > MAX_CSV_BYTES:
            raise TrajectoryError(f"{path}: the file has {size} bytes; a trajectory CSV may have at most "
                                  f"{MAX_CSV_BYTES} (docs/limits.md)")
        rows = []
        # utf-8-sig: a byte-order mark written by spreadsheets is not part of the first cell
        with path.open(newline="", encoding="utf-8-sig") as fh:
            for row in csv.reader(fh):
                if row and any(c.strip() for c in row):
                    rows.append(row)
                    if len(rows) > MAX_SAMPLES + 1:
                        raise TrajectoryError(f"{path}: more than {MAX_SAMPLES} rows (docs/limits.md)")
        return rows
    except FileNotFoundError:
        raise TrajectoryError(f"{path}: file not found") from None
    except IsADirectoryError:
        raise TrajectoryError(f"{path}: is a folder; expected a CSV file") from None
    except UnicodeDecodeError:
        raise TrajectoryError(f"{path}: not UTF-8 text; expected a CSV file") from None
    except (OSError, csv.Error) as exc:
        raise TrajectoryError(f"{path}: cannot read the CSV ({exc})") from None


def is_number(cell: str) -> bool:
    """``cell`` reads as a float (a header row has a cell that does not)."""
    try:
        float(cell)
        return True
    except ValueError:
        return False
