"""The example scenes shipped with texelpad (*.json, package data): `texelpad
scenes` lists them, `texelpad push --scene NAME` plays one."""
