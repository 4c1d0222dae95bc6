"""The seed's measured track: camera frames, reconstructed angles and energies (:mod:`.measurement`), and
FMU start states fitted to the frames (:mod:`.start_state`)."""
