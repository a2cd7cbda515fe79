"""Earth orientation and time scales: the one place where the inertial frame meets the rotating Earth.

Inertial frame: the GCRF (ICRS axes, geocentric). Earth-fixed frame: the ITRF. Every model of the project (truth,
radar, OD, acquisition trim, export and import) takes the rotation between them from :func:`gcrs_to_itrs`:

    r_ITRS = W(t) R(t) Q(t) r_GCRS        (IERS Conventions 2010, Eq. 5.1)

with Q the IAU 2000B precession-nutation including the frame bias (McCarthy & Luzum 2003; ERFA ``pnm00b``),
R = R3(ERA) the Earth rotation angle of UT1 (``era00``), W the polar motion (``pom00``, s' = 0), composed by ERFA's
``c2t00b``. IAU 2000B reproduces IAU 2006/2000A (``c2t06a``) to millimetres at a station (test/core/test_frames.py),
at a tenth of its cost per epoch. UT1 - UTC and the pole coordinates (x_p, y_p) come from the IERS EOP series
finals2000A (Bulletin A, with its predictions), as shipped by the astropy-iers-data package: nothing is downloaded at
run time. :func:`use_eop_file` (the scenario key ``earth.eop_file`` or the environment variable
``ROE_SEP_EOP_FILE``) points at a newer file of the same format.

Outside the table's epochs: one warning, then UT1 - UTC held at the table's nearest value (interpolated in
UT1 - TAI, continuous across leap seconds) and polar motion zero.

Time scales (:func:`utc_to_tai`, :func:`tai_to_tt`, :func:`tai_to_gps`, :func:`utc_to_ut1`): two-part Julian dates
(``jd1 + jd2``) as ERFA takes them; TAI - UTC from ERFA's leap-second table (``dat``), TT = TAI + 32.184 s,
GPS = TAI - 19 s. EME2000 (the mean equator and equinox of J2000.0, the CCSDS files' frame) is the GCRF rotated by
the frame bias B (``bi00``, 23 mas): :func:`gcrf_to_eme2000`.
"""

import os
import warnings
from functools import lru_cache

import erfa
import numpy as np
from numpy.typing import ArrayLike

from ..errors import EopError
from .constants import ARCSEC, SECONDS_PER_DAY

TT_MINUS_TAI = 32.184
"""TT - TAI [s]."""
TAI_MINUS_GPS = 19.0
"""TAI - GPS [s]."""
MJD_ZERO = 2400000.5
"""Julian date of MJD 0."""
EOP_ENV = "ROE_SEP_EOP_FILE"
"""Environment variable naming an EOP file (finals2000A format) that replaces the shipped one."""

_eop_path = None


def default_eop_file() -> str:
    """The finals2000A file shipped by astropy-iers-data (IERS Bulletin A with predictions)."""
    from astropy_iers_data import IERS_A_FILE

    return IERS_A_FILE


def use_eop_file(path: str | os.PathLike | None = None) -> None:
    """Take UT1 - UTC and polar motion from ``path`` (finals2000A format); None: ``$ROE_SEP_EOP_FILE`` or the shipped
    file. The file is read at once, so a bad one fails here with :class:`EopError`."""
    global _eop_path
    _eop_path = None if path is None else os.fspath(path)
    _read_eop(_current_eop_path())


def _current_eop_path() -> str:
    return _eop_path or os.environ.get(EOP_ENV) or default_eop_file()


@lru_cache(maxsize=4)
def _read_eop(path):
    """(mjd, ut1 - tai [s], x_p [rad], y_p [rad]) of a finals2000A file: the Bulletin A columns (format in the
    file's ReadMe: MJD cols 8-15, x_p 19-27, y_p 38-46 [arcsec], UT1-UTC 59-68 [s]); rows without UT1-UTC end it."""
    mjd, dut, xp, yp = [], [], [], []
    try:
        with open(path, encoding="ascii") as fh:
            for n, line in enumerate(fh, 1):
                if len(line) < 68 or not line[58:68].strip():
                    continue
                try:
                    mjd.append(float(line[7:15]))
                    xp.append(float(line[18:27]) if line[18:27].strip() else 0.0)
                    yp.append(float(line[37:46]) if line[37:46].strip() else 0.0)
                    dut.append(float(line[58:68]))
                except ValueError:
                    raise EopError(f"EOP file {path} line {n} is not in the finals2000A format") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise EopError(f"cannot read the EOP file {path}: {exc}") from None
    if len(mjd) < 2 or np.any(np.diff(mjd) <= 0):
        raise EopError(f"EOP file {path} holds no increasing series of daily UT1-UTC values (finals2000A format)")
    mjd = np.array(mjd)
    return mjd, np.array(dut) - _tai_minus_utc(MJD_ZERO, mjd), np.array(xp) * ARCSEC, np.array(yp) * ARCSEC


def _tai_minus_utc(jd1, jd2):
    """TAI - UTC [s] (ERFA ``dat``) at the UTC two-part Julian dates."""
    y, m, d, fd = erfa.jd2cal(jd1, jd2)
    return erfa.dat(y, m, d, fd)


_warned = set()


def earth_orientation(jd_utc: ArrayLike, seconds: ArrayLike = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """UT1 - UTC [s], x_p, y_p [rad] at UTC ``jd_utc`` + ``seconds``, linear in the table's daily values (UT1 - TAI
    interpolated, continuous across leap seconds). Beyond the table: warns once, holds UT1 - TAI, zero pole."""
    path = _current_eop_path()
    mjd_t, ut1_tai, xp_t, yp_t = _read_eop(path)
    jd1, jd2 = np.broadcast_arrays(np.asarray(jd_utc, dtype=float), np.asarray(seconds, dtype=float) / SECONDS_PER_DAY)
    mjd = (jd1 - MJD_ZERO) + jd2
    outside = (mjd < mjd_t[0]) | (mjd > mjd_t[-1])
    if np.any(outside) and path not in _warned:
        _warned.add(path)
        warnings.warn(f"epoch MJD {float(mjd[outside].flat[0]):.1f} is outside the EOP table {path} (MJD "
                      f"{mjd_t[0]:.0f}-{mjd_t[-1]:.0f}): UT1-TAI held at its last value, polar motion zero; "
                      f"point the scenario's earth.eop_file (or ${EOP_ENV}) at a newer finals2000A file",
                      RuntimeWarning, stacklevel=2)
    dut = np.interp(mjd, mjd_t, ut1_tai) + _tai_minus_utc(jd1, jd2)
    xp = np.where(outside, 0.0, np.interp(mjd, mjd_t, xp_t))
    yp = np.where(outside, 0.0, np.interp(mjd, mjd_t, yp_t))
    return dut, xp, yp


def utc_to_tai(jd1: ArrayLike, jd2: ArrayLike = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """TAI two-part Julian date of a UTC one (ERFA ``utctai``, its leap seconds)."""
    return erfa.utctai(jd1, jd2)


def tai_to_tt(jd1: ArrayLike, jd2: ArrayLike = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """TT = TAI + 32.184 s (ERFA ``taitt``)."""
    return erfa.taitt(jd1, jd2)


def tai_to_gps(jd1: ArrayLike, jd2: ArrayLike = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """GPS time = TAI - 19 s, as a two-part Julian date."""
    return jd1, np.asarray(jd2, dtype=float) - TAI_MINUS_GPS / SECONDS_PER_DAY


def utc_to_tt(jd1: ArrayLike, jd2: ArrayLike = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """TT of UTC: :func:`utc_to_tai` then :func:`tai_to_tt`."""
    return tai_to_tt(*utc_to_tai(jd1, jd2))


def utc_to_ut1(jd1: ArrayLike, jd2: ArrayLike = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """UT1 of UTC with UT1 - UTC from the EOP table (:func:`earth_orientation`, ERFA ``utcut1``)."""
    dut = earth_orientation(jd1, np.asarray(jd2, dtype=float) * SECONDS_PER_DAY)[0]
    return erfa.utcut1(jd1, jd2, dut)


def gcrs_to_itrs(jd_utc: ArrayLike, seconds: ArrayLike = 0.0) -> np.ndarray:
    """Rotation GCRS -> ITRS ``(..., 3, 3)`` at UTC Julian date ``jd_utc`` + ``seconds`` [s] (module docstring:
    ERFA ``c2t00b`` with the IERS EOP). r_ITRS = M r_GCRS; broadcasts over both arguments."""
    jd1, jd2 = np.broadcast_arrays(np.asarray(jd_utc, dtype=float), np.asarray(seconds, dtype=float) / SECONDS_PER_DAY)
    dut, xp, yp = earth_orientation(jd1, jd2 * SECONDS_PER_DAY)
    tt1, tt2 = utc_to_tt(jd1, jd2)
    ut1, ut2 = erfa.utcut1(jd1, jd2, dut)
    return erfa.c2t00b(tt1, tt2, ut1, ut2, xp, yp)


def gcrf_to_eme2000() -> np.ndarray:
    """The frame bias B ``(3, 3)`` (IAU 2000, ERFA ``bp00``'s rb, IERS Conventions 2010 Eq. 5.21): r_EME2000 =
    B r_GCRF."""
    return erfa.bp00(2451545.0, 0.0)[0]
