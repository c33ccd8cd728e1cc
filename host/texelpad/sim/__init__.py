"""The simulated boards: a board's firmware running on this machine, reached
over the link as a board is (a pty), and deployed into as a board is.

    virtual    the virtual board: the MicroPython unix port on a pty
               (VirtualBoard, open_virtual: deployed and playing as at
               power-up; the registry `texelpad ports` reads)
    emulated   the emulated Raspberry Pi Pico: the real firmware on rp2040js
               (../shared/instruments; EmulatedPico, open_emulated)

Above the link and deploy (docs/architecture.md): a simulated board connects
through texelpad.link and deploys itself with texelpad.deploy; neither of
those knows it. Each module is imported by its full name (nothing here is
imported with the package), so `texelpad.sim.virtual` loads neither the
emulator's code nor deploy until they are used.
"""
