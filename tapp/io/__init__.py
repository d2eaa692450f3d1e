"""Formats: every file tapp reads or writes, between the kernels and the programs.

The input side: TOML reading (:mod:`tapp.io.tomlfile`) and the declared schemas of every input
file (:mod:`tapp.io.schema`, rendered as the reference pages by :mod:`tapp.io.reference`); the
input tables several programs share, stations, force models, noise models and initial orbits
(:mod:`tapp.io.stations_file`, :mod:`tapp.io.models_file`, :mod:`tapp.io.noise_file`,
:mod:`tapp.io.orbits`); a user's IERS EOP table and the ``eop`` key (:mod:`tapp.io.eop_file`);
a mission's own trajectory, SPICE SPK or CCSDS OEM (:mod:`tapp.io.trajectory_file`). The
output side: atomic writes and the output sets of a run (:mod:`tapp.io.atomic`,
:mod:`tapp.io.outputs`), the study's observation files
(:mod:`tapp.io.obsfile`), the tapes between the programs (:mod:`tapp.io.tape`), the CCSDS
messages (:mod:`tapp.io.ccsds`) and SPICE SPK files (:mod:`tapp.io.spk`). Nothing here
computes a program's answer.
"""
