"""The Textual frontend: the app and its panels."""
