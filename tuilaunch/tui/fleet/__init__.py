"""One TUI over several sessions (`tuilaunch attach a:x b:y`): app.py lays out a tree and a
pane per session and sends the keys to the selected one's session view (session_view.py)."""
