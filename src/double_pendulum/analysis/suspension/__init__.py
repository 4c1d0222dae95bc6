"""A damped pivot suspension (scenario ``suspension_transfer``): its linear response (:mod:`.response`), its
identification from the measured decay (:mod:`.identification`), the decay-rate map (:mod:`.decay_map`),
the energy flow (:mod:`.energy_flow`), the study's summaries (:mod:`.transfer`) and the report."""
