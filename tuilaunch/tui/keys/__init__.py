"""The keys a session's node takes: `i` typing into it, `g` a restart under a tool, `c` its
command line (keyboard.py's NodeKeyboard), what that keyboard needs of its session
(host.py), and key events as a terminal's bytes (key_bytes.py)."""
