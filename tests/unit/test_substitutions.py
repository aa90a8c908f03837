"""SimpleSubstitution operators and the path helpers of the DSL."""

from __future__ import annotations

import os

from tuilaunch.engine.packages import package_share

from ..conftest import plan_of


def test_plus_and_slash_between_substitutions_and_strings(write):
    path = write("""
from simple_launch import SimpleLauncher
def generate_launch_description():
    sl = SimpleLauncher()
    robot = sl.declare_arg('robot', 'r1')
    sl.node('tuilaunch_demos', 'talker', parameters={
        'plus': robot + '.xacro',
        'rplus': 'pre_' + robot,
        'slash': '/opt' / robot / 'urdf',
        'chain': (robot + '_a') / (robot + '_b'),
        'name_join': sl.name_join(robot, '.urdf'),
        'path_join': sl.path_join('/base', robot, 'x.yaml'),
        'share': sl.find('tuilaunch_demos'),
        'found': sl.find('tuilaunch_demos', 'turret.xacro'),
        'in_dir': sl.find('tuilaunch_demos', 'talker.yaml', 'config'),
        'lazy': sl.find('tuilaunch_demos', robot + '.yaml', 'config'),
        'absolute': sl.find(None, '/etc/hostname'),
    })
    return sl.launch_description()
""")
    share = str(package_share("tuilaunch_demos"))
    params = plan_of(path, robot="bot").processes[0].parameters
    assert params == {
        "plus": "bot.xacro", "rplus": "pre_bot", "slash": "/opt/bot/urdf",
        "chain": "bot_a/bot_b", "name_join": "bot.urdf", "path_join": "/base/bot/x.yaml",
        "share": share, "found": os.path.join(share, "urdf", "turret.xacro"),
        "in_dir": os.path.join(share, "config", "talker.yaml"),
        "lazy": os.path.join(share, "config", "bot.yaml"), "absolute": "/etc/hostname",
    }


def test_numbers_from_arguments_are_typed_like_ros_does(write):
    path = write("""
from simple_launch import SimpleLauncher
def generate_launch_description():
    sl = SimpleLauncher()
    sl.node('tuilaunch_demos', 'talker', parameters={
        'i': sl.declare_arg('i', 1), 'f': sl.declare_arg('f', 1.5),
        'b': sl.declare_arg('b', False), 's': sl.declare_arg('s', 'text'),
        'l': sl.declare_arg('l', [1, 2])})
    return sl.launch_description()
""")
    assert plan_of(path).processes[0].parameters == {
        "i": 1, "f": 1.5, "b": False, "s": "text", "l": [1, 2]}
