"""The astrodynamic programs that SEARCH (:mod:`search`) and ITER (:mod:`iter`) drive.

:mod:`tapp.targeting.program`: the B-plane program (injection velocity -> B·R, B·T, flight
time) and its search files; :mod:`tapp.targeting.lunar_departure`: the lunar departure
targeting of a tracking scenario; :mod:`tapp.targeting.launch_azimuth`: the cheap direct-ascent
body of the seed's ITER examples.
"""
