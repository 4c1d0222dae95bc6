"""The pendulum on its suspension split in two FMUs (scenario ``cosimulation``): the study
(:mod:`.cosimulation`), the added-mass stability limit (:mod:`.stability`) and the report."""
