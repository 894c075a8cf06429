"""
Files that a request may name: only those inside the share folder of an installed package.

A request names a file (a robot, a world) or a folder (where to look for them) by uri:
package://<package>/<path> by the package's share, or file://<path> when the path lies in the
share of the package it names (.../share/<package>/...). Paths with '..', links that lead out of
the share, other schemes and names too long are refused before anything is opened, so that no
request makes the world read a file an installed package does not hold.
"""

import os

from service_tutorial.sim.urdf.meshes import share_holding
from service_tutorial.sim.validation import quoted

MAX_URI_LENGTH = 4096


class PackageFileError(ValueError):
    """A uri that names nothing a request may read; the message names the uri and why."""


class PackageIndex:
    """
    The installed packages as the ROS side knows them: a package's share, and every share.

    Called with a package's name it returns that package's share folder, as ament's
    get_package_share_directory does (and raises as it does); shares() returns
    {package: real share folder} of every installed package, for what looks in all of them
    (an SDF model:// uri, in every package's models/ folder).
    """

    def __init__(self, share_of, shares):
        """Answer with share_of(package) and shares(), the ROS side's two functions."""
        self._share_of = share_of
        self._shares = shares

    def __call__(self, package):
        """Return the share folder of an installed package."""
        return self._share_of(package)

    def shares(self):
        """Return {package: real share folder} of every installed package."""
        return self._shares()


def installed_shares_of(package_resolver):
    """Return {package: share} a package resolver lists; {} for one that only resolves."""
    listing = getattr(package_resolver, 'shares', None)
    return listing() if listing is not None else {}


def confined_path(uri, package_share, *, folder=False, what='uri'):
    """
    Return the real path of the file (or folder) a uri names inside a package's share.

    package_share maps a package name to its share folder (ament's get_package_share_directory);
    folder: True for a folder, False for a file, None for either; what names the uri in the
    messages.
    Raise PackageFileError if the uri is malformed, leaves the share or names nothing.
    """
    shown = quoted(uri)
    if len(uri) > MAX_URI_LENGTH:
        raise PackageFileError(f'{what} {shown} is longer than {MAX_URI_LENGTH} characters')
    scheme, separator, rest = uri.partition('://')
    if not separator or scheme not in ('package', 'file'):
        raise PackageFileError(f'{what} {shown} is neither package://<package>/<path> nor '
                               'file://<absolute path>')
    if '..' in rest.split('/') or '\0' in rest:
        raise PackageFileError(f"{what} {shown} must not contain '..'")
    if scheme == 'package':
        package, _, relative = rest.partition('/')
        share = package_share_of(package, package_share, f'{what} {shown}')
        candidate = os.path.join(share, relative)
    else:
        if not rest.startswith('/'):
            raise PackageFileError(f'{what} {shown} is not an absolute path')
        candidate = os.path.normpath(rest)
        share = share_holding(candidate, package_share)
        if share is None:
            raise PackageFileError(f'{what} {shown} lies outside the share folders of the '
                                   'installed packages')
    path = os.path.realpath(candidate)
    if not within(path, share):
        raise PackageFileError(f'{what} {shown} leads outside the share folder of its package')
    if folder and not os.path.isdir(path):
        raise PackageFileError(f'{what} {shown} names no folder')
    if folder is False and not os.path.isfile(path):
        raise PackageFileError(f'{what} {shown} names no file')
    if folder is None and not os.path.exists(path):
        raise PackageFileError(f'{what} {shown} names no file or folder')
    return path


def package_share_of(package, package_share, named):
    """Return the real share folder of a package, or refuse the uri (named) that names it."""
    if not package or not all(character.isalnum() or character == '_'
                              for character in package):
        raise PackageFileError(f'{named} names no valid package')
    try:
        share = package_share(package)
    except Exception:  # ament's PackageNotFoundError, or a resolver's own error
        share = None
    if not share or not os.path.isdir(share):
        raise PackageFileError(f'{named}: package {quoted(package)} is not installed')
    return os.path.realpath(share)


def within(path, folder):
    """Return True if the real path lies inside the real folder (or is it)."""
    folder = os.path.realpath(folder)
    return path == folder or path.startswith(folder.rstrip(os.sep) + os.sep)


def package_uri(path, package_share):
    """Return the package:// uri of a real path inside a package's share, or None."""
    share = share_holding(path, package_share)
    if share is None or not within(path, share):
        return None
    package = os.path.basename(share)
    return f'package://{package}/{os.path.relpath(path, share)}'
