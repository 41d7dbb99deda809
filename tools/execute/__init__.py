"""The execution layer: send a schedule to simulated or physical robots over MQTT.

:mod:`.protocol` (topics, messages, schemas, signatures), :mod:`.broker` (the embedded broker and
clients), :mod:`.robot` (the simulated robot), :mod:`.executor` (the synchronous release of steps),
:mod:`.journal` (the crash-safe record of a run), :mod:`.session` (one ``bille run``). The
protocol is documented in docs/execution.md.
"""
