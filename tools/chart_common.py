"""Pieces shared by qsil's grid scripts (candidates_grid.py, slices_grid.py): their command line
(SUMMARY.json OUT.png), reading the summary, and finishing and saving the figure atomically.

Imported from the script's own directory (tools/, <build>/share/qsil or <prefix>/share/qsil).
"""
import json
import os
import sys


def run(draw, usage):
    """Command line SUMMARY.json OUT.png (else exits with `usage`): draw(summary, directory of the
    summary) returns (figure, legend handles, legend columns, title, top of the layout); the
    legend goes below, the title above, and OUT.png is written atomically (a temporary PNG beside
    it, renamed)."""
    if len(sys.argv) != 3:
        sys.exit(usage)
    summary_path, out_path = sys.argv[1], sys.argv[2]
    with open(summary_path) as f:
        summary = json.load(f)
    fig, handles, ncol, title, top = draw(summary, os.path.dirname(summary_path))
    fig.legend(handles=handles, loc="lower center", ncol=ncol, fontsize=9, frameon=False)
    fig.suptitle(title, fontsize=11)
    fig.tight_layout(rect=(0, 0.05, 1, top))
    fig.savefig(out_path + ".tmp.png", dpi=100)
    os.replace(out_path + ".tmp.png", out_path)
