"""CCSDS Navigation Data Messages that tapp reads and writes (formats floor: files only).

:mod:`tapp.io.ccsds.tdm`: Tracking Data Messages (observations). The trajectory's Orbit
Ephemeris Message is written by :mod:`tapp.io.ccsds.oem`; a mission's OEM (KVN or XML) is read
by :mod:`tapp.io.ccsds.oem_read`.
"""
