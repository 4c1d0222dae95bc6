"""Which losses drain the real pendulum (scenario ``loss_identification``): loss mechanisms fitted to the
measured energy (:mod:`.identification`), what the fits support (:mod:`.claims`) and the report."""
