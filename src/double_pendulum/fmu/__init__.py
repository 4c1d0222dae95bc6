"""Build the FMU and run the component: through fmpy (:mod:`.runner`), libcosim (:mod:`.hosts`)
or in-process (:mod:`.simulate`). Not bundled into the FMU; :mod:`.build` decides what is.
"""
