"""`tuilaunch serve`: the command (command.py), its guard (token, cookie, Host and Origin),
the pages (web.py, textual-serve) and the TUI process of each browser tab (tabs.py)."""
