"""The reconfiguration loop of the paper (Methods, "Temporal A*"): the loop (:mod:`.reconfigure`),
its state (:mod:`.loopstate`, :mod:`.legs`), the sequence of jobs (:mod:`.sequence`), one part per
step (:mod:`.allocation`, :mod:`.transfer`, :mod:`.goals`, :mod:`.manipulation`, :mod:`.motion`,
with M* and LaCAM* as motion layers in :mod:`.joint_motion`), and the options the methods that
run it share (:mod:`.loop_options`)."""
