"""Open an FMU in FMPy's GUI, simulate it with the GUI's defaults and save a screenshot of the window.

Usage (under a display, e.g. ``xvfb-run``): ``python tests/fmpy_gui_shot.py FMU PNG``. Prints one JSON line: the
variables the GUI plotted, the rows of its figure and the error its plotting raised (None). The GUI is driven
as a user would: ``fmpy.gui.main``'s window, ``load`` (File > Open), then ``startSimulation`` (the Simulate
button); the only hook is a wrapper around fmpy's ``create_plotly_figure`` that records what it was given.
"""

from __future__ import annotations

import json
import sys


def main(fmu: str, png: str) -> int:
    import fmpy.util
    from fmpy.gui.MainWindow import MainWindow
    from PySide6.QtCore import QTimer
    from PySide6.QtWidgets import QApplication

    report: dict = {"plotted": [], "rows": 0, "error": None}
    plot = fmpy.util.create_plotly_figure

    def recording(result, names=None, **options):  # the GUI imports it from fmpy.util at each redraw
        try:
            figure = plot(result, names=names, **options)
        except Exception as error:  # what the GUI would swallow: report it
            report["error"] = f"{type(error).__name__}: {error}"
            raise
        report["plotted"] = list(names or [])
        report["rows"] = len(figure.data)
        return figure

    fmpy.util.create_plotly_figure = recording
    app = QApplication([sys.argv[0]])
    window = MainWindow()
    window.resize(1280, 860)
    window.show()
    window.load(fmu)
    state = {"pages": 0}

    def loaded(ok: bool) -> None:
        state["pages"] += 1

    window.ui.resultWebEngineView.loadFinished.connect(loaded)
    window.startSimulation()

    def poll() -> None:
        if window.simulationThread is None and state["pages"]:
            # simulationFinished ran (it drops the thread) and the plot page loaded: let plotly draw, then shoot
            QTimer.singleShot(4000, shoot)
        else:
            QTimer.singleShot(200, poll)

    def shoot() -> None:
        report["saved"] = window.grab().save(png)
        app.quit()

    QTimer.singleShot(200, poll)
    QTimer.singleShot(120_000, app.quit)  # never hang the test
    app.exec()
    report["pages"] = state["pages"]
    print(json.dumps(report))
    return 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:3]))
