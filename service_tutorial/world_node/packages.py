"""The installed ament packages: the one place that lists them and finds their share folders."""

import os

from ament_index_python.packages import get_package_share_directory
from ament_index_python.packages import get_packages_with_prefixes
from service_tutorial.sim.package_files import PackageIndex

PACKAGE = 'service_tutorial'


def installed_shares():
    """Return {package: real share folder} of every installed package, sorted by name."""
    shares = {}
    for package, prefix in sorted(get_packages_with_prefixes().items()):
        share = os.path.join(prefix, 'share', package)
        if _valid_package(package) and os.path.isdir(share):
            shares[package] = os.path.realpath(share)
    return shares


# Called with a package's name, its share folder (or it raises as the ament index does); its
# shares() lists every installed package, for SDF's model:// in their models/ folders.
package_share = PackageIndex(get_package_share_directory, installed_shares)


def own_share():
    """Return this package's share folder."""
    return get_package_share_directory(PACKAGE)


def _valid_package(package):
    return bool(package) and all(character.isalnum() or character == '_'
                                 for character in package)
