"""The measured energy decay (scenario ``energy_decay``): decay laws and weighted fits (:mod:`.fit`), the
summary and track table (:mod:`.summary`), the error budget (:mod:`.error_budget`), the noise model of b
(:mod:`.noise`), the non-stationarity study (:mod:`.stationarity`) and the report."""
