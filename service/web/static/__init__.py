"""Static files of the web page (a package only so the wheel carries them as package data)."""
