"""Reading, writing and plotting helpers shared by the scripts in tools/.

The scripts run as `/usr/bin/python3 tools/X.py` and find this module next to themselves (they put
their own folder on sys.path before importing it).
"""
import csv

import numpy as np


def read_csv_columns(path):
    """A CSV file of numbers as {column name: numpy array} ({} for a file without rows)."""
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]} if rows else {}


def write_csv_rows(path, rows, fieldnames=None):
    """Rows (dicts) as a CSV file; the columns are those of the first row unless fieldnames are given."""
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fieldnames if fieldnames is not None else list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)


def finish_axes(ax, xlabel=None, ylabel=None, title=None, **legend_options):
    """Label a panel (the labels not None), draw its legend (with legend_options) and a light grid."""
    if xlabel is not None:
        ax.set_xlabel(xlabel)
    if ylabel is not None:
        ax.set_ylabel(ylabel)
    if title is not None:
        ax.set_title(title)
    ax.legend(**legend_options)
    ax.grid(True, alpha=0.3)


def save_figure(fig, path, dpi):
    """Lay out a figure, write it to path and close it (the scripts draw many figures in one run)."""
    import matplotlib.pyplot as plt
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
