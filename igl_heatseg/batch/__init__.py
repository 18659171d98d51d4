"""Batches of meshes on Dask: ``igl-heatseg batch INPUTS... -o OUT`` and :func:`run_batch`.

Modules:

``discover``  INPUTS (files, folders, glob patterns) to meshes and their output folders
``jobs``      the single-mesh jobs the CLI commands run too, and the table of job kinds
``server``    the per-worker job server: each mesh in a forked child, timeout, memory limit
``worker``    the task a Dask worker runs for one mesh (no Dask needed)
``summary``   ``summary.csv``, ``summary.json`` and the ``index.html`` gallery
``runner``    :func:`run_batch`: resumption, Dask orchestration, progress

Dask is the ``batch`` extra (``pip install 'igl_heatseg[batch]'``), imported only when a batch
runs: importing this package does not load it.

Examples
--------
From a notebook, with a client of your own::

    from dask.distributed import Client
    from igl_heatseg.batch import run_batch
    client = Client("tcp://scheduler:8786")
    res = run_batch(["parts/"], "out/", command="run", client=client, timeout=300)
    res.counts, res.failed
"""

from __future__ import annotations

from .discover import MESH_SUFFIXES, MeshInput, discover
from .jobs import JOB_KINDS, JobKind, JobOutput, job_kind, run_file, segment_file, write_pictures
from .runner import INSTALL_HINT, BatchResult, parse_memory, run_batch
from .summary import COLUMNS, FAILED_STATUSES, OK_STATUSES
from .worker import process_mesh

__all__ = [
    "run_batch",
    "BatchResult",
    "discover",
    "MeshInput",
    "MESH_SUFFIXES",
    "JOB_KINDS",
    "JobKind",
    "job_kind",
    "segment_file",
    "run_file",
    "JobOutput",
    "write_pictures",
    "process_mesh",
    "parse_memory",
    "COLUMNS",
    "OK_STATUSES",
    "FAILED_STATUSES",
    "INSTALL_HINT",
]
