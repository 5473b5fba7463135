"""Qt widgets of the studio: viewport adapters, panels, plots. Never imports torch."""
