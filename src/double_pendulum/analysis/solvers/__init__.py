"""The solver studies (scenarios ``work_precision`` and ``stability``): cached reference solutions
(:mod:`.reference`), the work-precision cases (:mod:`.work_precision`) and the hard cases with their pass
criteria (:mod:`.stability_cases`)."""
