"""The pivot driven through the FMU's inputs (scenario ``base_excitation``): input signals and runs
(:mod:`.drive`), the linear theory (:mod:`.theory`), the three studies (:mod:`.study`) and the report."""
