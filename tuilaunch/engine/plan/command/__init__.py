"""A process's command: its line as ros2 launch builds it (command_line.py), the launch
prefixes put before it (prefix.py), and the one shell line that runs it by hand
(shell_command.py)."""
