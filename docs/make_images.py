"""Regenerate the pictures of docs/commands.md with the command line (run from the repository root).

    python docs/make_images.py

The report's screenshot (docs/images/report.png) is taken by the browser test:
``LINKAGEKIT_SCREENSHOTS=1 pytest tests/test_report_browser.py``.
"""

from __future__ import annotations

from pathlib import Path

from linkagekit.cli import main

ROOT = Path(__file__).resolve().parents[1]
IMAGES = ROOT / "docs" / "images"

COMMANDS = [
    ["plot", "examples/jansen_leg.yaml", "-o", "docs/images/plot_jansen.png"],
    ["plot", "examples/seed003_ex21.yaml", "--at", "90,180,270", "-o", "docs/images/plot_seed003_at.png"],
    ["plot", "examples/seed000_fourbar.yaml", "--modes", "--at", "30", "-o", "docs/images/plot_modes_seed000.png"],
    ["plot", "examples/triad_six_modes.yaml", "--modes", "--at", "57.08", "-o", "docs/images/plot_modes_triad.png"],
    ["plot", "examples/excavator_boom.yaml", "-o", "docs/images/plot_excavator.png"],
    [
        "synthesize",
        "examples/targets/d_path.csv",
        "--units",
        "mm",
        "--seconds",
        "20",  # as docs/commands.md shows it
        "-o",
        "/tmp/d_path_fourbar.yaml",
        "--plot",
        "docs/images/synthesize_dpath.png",
    ],
    [
        "synthesize",
        "examples/targets/guided_poses.csv",
        "--task",
        "motion",
        "--units",
        "mm",
        "--min-transmission",
        "20",
        "-o",
        "/tmp/guided_fourbar.yaml",
        "--plot",
        "docs/images/synthesize_motion.png",
    ],
    [
        "synthesize",
        "examples/targets/log_function.csv",
        "--task",
        "function",
        "--free-offsets",
        "-o",
        "/tmp/log_function.yaml",
        "--plot",
        "docs/images/synthesize_function.png",
    ],
    [
        "plot",
        "examples/slider_crank.yaml",
        "-q",
        "torques",
        "-q",
        "bearings",
        "-o",
        "docs/images/plot_quantities_slider_crank.png",
    ],
    [
        "plot",
        "examples/slider_crank.yaml",
        "--time",
        "0:0.3:0.001",
        "--motor",
        "3,60",
        "-q",
        "crank.omega",
        "-q",
        "T[crank]",
        "-o",
        "docs/images/plot_simulate_slider_crank.png",
    ],
    ["plot", "examples/seed003_ex21.yaml", "-o", "docs/images/check_seed003.png"],  # the range check reports
    ["animate", "examples/whitworth_quick_return.yaml", "--frames", "36", "-o", "docs/images/animate_whitworth.gif"],
]

if __name__ == "__main__":
    import os

    os.chdir(ROOT)
    IMAGES.mkdir(exist_ok=True)
    for cmd in COMMANDS:
        assert main(cmd) == 0, cmd
        print(cmd[-1])
