"""Reports (product item 5): one run directory or a sweep/batch table → HTML + PNG.

``build_report(run_dir) -> Path``                       run_dir/report.html (:mod:`.build`)
``build_sweep_report(table_csv, parameters=None) -> Path``  <table>_report.html next to
                                                         sweep.csv / batch.csv (:mod:`.sweep`)

Heavy libraries (matplotlib, pyvista, jinja2) are imported inside the functions.
"""

from __future__ import annotations

from flexnet_fe.report.build import build_report
from flexnet_fe.report.sweep import build_sweep_report

__all__ = ["build_report", "build_sweep_report"]
