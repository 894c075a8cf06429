"""
Where a world lies on the Earth: SDF's <spherical_coordinates>, as gz-math converts positions.

A world with <spherical_coordinates> has its origin at a latitude, longitude and elevation on
the WGS84 ellipsoid, its x axis east and y north (ENU), turned by heading_deg. A world position
becomes a latitude, longitude and altitude as gz-sim's NavSat sensor has it (gz-math's
SphericalCoordinates, LOCAL2 to SPHERICAL): rotated by the heading into east, north, up, moved
to Earth-centred coordinates (ECEF) from the origin's, and turned into geodetic ones by
Bowring's formula. A velocity is turned by the heading alone.
"""

from dataclasses import dataclass
import math

import numpy as np

# The WGS84 ellipsoid: semi-major and semi-minor axes in m.
EQUATORIAL_AXIS = 6378137.0
POLAR_AXIS = 6356752.314245
_ECCENTRICITY = math.sqrt(1.0 - POLAR_AXIS ** 2 / EQUATORIAL_AXIS ** 2)
_SECOND_ECCENTRICITY = math.sqrt(EQUATORIAL_AXIS ** 2 / POLAR_AXIS ** 2 - 1.0)


@dataclass(frozen=True)
class SphericalCoordinates:
    """A world's origin on the Earth and the heading of its x axis (SDF's defaults)."""

    latitude_deg: float = 0.0
    longitude_deg: float = 0.0
    elevation: float = 0.0  # m above the ellipsoid
    heading_deg: float = 0.0  # of the world's x axis, counter-clockwise from east

    def spherical_from_local(self, position):
        """Return (latitude deg, longitude deg, altitude m) of a world position (x, y, z)."""
        east_north_up = self._turned(position)
        ecef = _ecef(math.radians(self.latitude_deg), math.radians(self.longitude_deg),
                     self.elevation) + self._enu_to_ecef() @ east_north_up
        latitude, longitude, altitude = _geodetic(ecef)
        return math.degrees(latitude), math.degrees(longitude), altitude

    def global_from_local_velocity(self, velocity):
        """Return a world velocity as (east, north, up)."""
        return self._turned(velocity)

    def _turned(self, vector):
        # gz-math negates the heading: a positive heading turns the world clockwise from ENU.
        heading = -math.radians(self.heading_deg)
        cos, sin = math.cos(heading), math.sin(heading)
        x, y, z = (float(value) for value in vector)
        return np.array([x * cos + y * sin, -x * sin + y * cos, z])

    def _enu_to_ecef(self):
        latitude, longitude = math.radians(self.latitude_deg), math.radians(self.longitude_deg)
        sin_lat, cos_lat = math.sin(latitude), math.cos(latitude)
        sin_lon, cos_lon = math.sin(longitude), math.cos(longitude)
        return np.array([[-sin_lon, -cos_lon * sin_lat, cos_lon * cos_lat],
                         [cos_lon, -sin_lon * sin_lat, sin_lon * cos_lat],
                         [0.0, cos_lat, sin_lat]])


def _ecef(latitude, longitude, altitude):
    """Return the Earth-centred position of geodetic coordinates (rad, rad, m)."""
    curvature = EQUATORIAL_AXIS / math.sqrt(1.0 - (_ECCENTRICITY * math.sin(latitude)) ** 2)
    return np.array([
        (altitude + curvature) * math.cos(latitude) * math.cos(longitude),
        (altitude + curvature) * math.cos(latitude) * math.sin(longitude),
        (POLAR_AXIS ** 2 / EQUATORIAL_AXIS ** 2 * curvature + altitude) * math.sin(latitude)])


def _geodetic(ecef):
    """Return (latitude rad, longitude rad, altitude m) of an Earth-centred position."""
    x, y, z = ecef
    p = math.hypot(x, y)
    theta = math.atan2(z * EQUATORIAL_AXIS, p * POLAR_AXIS)
    latitude = math.atan2(z + _SECOND_ECCENTRICITY ** 2 * POLAR_AXIS * math.sin(theta) ** 3,
                          p - _ECCENTRICITY ** 2 * EQUATORIAL_AXIS * math.cos(theta) ** 3)
    curvature = EQUATORIAL_AXIS / math.sqrt(1.0 - (_ECCENTRICITY * math.sin(latitude)) ** 2)
    altitude = p / math.cos(latitude) - curvature if abs(math.cos(latitude)) > 1e-12 else \
        abs(z) - POLAR_AXIS
    return latitude, math.atan2(y, x), altitude
