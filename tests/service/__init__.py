"""The REST service: every endpoint, the rules it shares with the library, hostile clients,
faults and load on the real server, the solver slots, the playground in a browser, the
schema's properties, and the two commands on a fresh checkout."""
