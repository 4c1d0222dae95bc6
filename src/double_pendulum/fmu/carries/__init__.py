"""What an FMU carries besides its code, written at build: what a tool shows of it.

:mod:`.presentation` puts it together: the documentation page (:mod:`.documentation`, which renders the
model's docstrings with :mod:`.docstring_html` and their TeX with :mod:`.tex_html`, and states what each
binary needs of the system with :mod:`.elf_needs`), the result plot (:mod:`.doc_plot`), the reference
result (:mod:`.reference_result`), the icon (:mod:`.icons`) and the terminals (:mod:`.terminals`). The
plots and the reference result are computed in-process by the masters (:mod:`double_pendulum.fmu.masters`);
nothing here builds an FMU (the build, :mod:`double_pendulum.fmu.build`, calls this).
"""
