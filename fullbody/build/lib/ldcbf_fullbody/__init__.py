"""ldcbf_fullbody: the LDCBF footstep controller (``ldcbf_nav``) walking a
full humanoid (Unitree G1) in MuJoCo, with placo's whole-body IK.

``python3 -m ldcbf_fullbody run SCENARIO --out DIR``; docs/fullbody.md."""
