// The benchmark's model, baked into the binary: lp_baked_model .. lp_baked_model_end, then a 0.
        .section .rodata
        .global lp_baked_model
        .global lp_baked_model_end
lp_baked_model:
        .incbin LP_MODEL_PATH
lp_baked_model_end:
        .byte 0
        .section .note.GNU-stack,"",%progbits
