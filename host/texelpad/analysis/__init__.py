"""Pure analysis of maps and telemetry (numpy; never the link).

    spectrum     spectra of friction maps
    figures      the PNGs (render, demo)
    precision    per-sample error bounds of the device engines, in PWM steps
    hard_cases   the hard-case suite every engine is measured on
"""
