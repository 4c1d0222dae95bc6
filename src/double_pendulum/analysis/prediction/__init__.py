"""FMU predictions of the measured track (scenario ``measured_vs_sim``): runs from a start frame, position
errors and horizons (:mod:`.comparison`), and the report."""
