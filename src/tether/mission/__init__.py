"""One exploration mission under every connectivity paradigm, measured side by side."""
