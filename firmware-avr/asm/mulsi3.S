; __mulsi3: the low 32 bits of a 32 x 32-bit product on the ATmega328P
; (a in r22..r25, b in r18..r21, product out in r22..r25), with libgcc's
; calling convention and register use (r26, r27 and r0 clobbered, r1 left
; zero, r18..r21 and r30, r31 kept), without libgcc's nested calls: its
; __mulsi3 pushes two bytes and calls __muluhisi3, which calls __umulhisi3.
; Here the ten 8 x 8-bit products that reach the low 32 bits are summed
; in place: a2 b0, a2 b1 and a3 b0 first (into bytes 2 and 3, where a2 and
; a3 were), then those of a0 and a1 (kept in r26, r27). The same product,
; wrapping, for signed and unsigned operands; the `costs` bench checks a
; sweep against the host's.
;
; First a shorter way for two operands below 2^16, the four products of
; their two low bytes: 24 cycles to the `ret` against 41, and 6 more for
; the others. Of the planner step's ~66 products (`cargo xtask
; avr-profile` counts them), 64 % are of two such operands, 32 % of two
; 16-bit ones of which one or both are negative (high bytes 0xff: telling
; those apart too costs about as much as their shorter way would save)
; and 4 % wider.

; One 8 x 8-bit product added at bytes 1 and 2 (its carry into byte 3;
; r1 cleared to be the zero), at bytes 2 and 3, or its low byte at byte 3.
	.macro	at12 a, b
	mul	\a, \b
	add	r23, r0
	adc	r24, r1
	eor	r1, r1
	adc	r25, r1
	.endm
	.macro	at23 a, b
	mul	\a, \b
	add	r24, r0
	adc	r25, r1
	.endm
	.macro	at3 a, b
	mul	\a, \b
	add	r25, r0
	.endm

	.section .text.libgcc.mul,"ax",@progbits
	.global	__mulsi3
	.type	__mulsi3, @function
__mulsi3:
	mov	r26, r24		; both below 2^16 (high bytes all 0)?
	or	r26, r25
	or	r26, r20
	or	r26, r21
	brne	.Lfull
	movw	r26, r22		; a0, a1
	mul	r27, r19		; a1 b1 -> bytes 2, 3
	movw	r24, r0
	mul	r26, r18		; a0 b0 -> bytes 0, 1
	movw	r22, r0
	at12	r26, r19		; a0 b1
	at12	r27, r18		; a1 b0
	ret
.Lfull:
	movw	r26, r22		; a0, a1
	mul	r25, r18		; a3 b0 -> byte 3
	mov	r25, r0
	mul	r24, r19		; a2 b1 -> byte 3
	add	r25, r0
	mul	r24, r18		; a2 b0 -> bytes 2, 3
	mov	r24, r0
	add	r25, r1
	mul	r26, r18		; a0 b0 -> bytes 0, 1
	movw	r22, r0
	at12	r26, r19		; a0 b1
	at12	r27, r18		; a1 b0
	at23	r26, r20		; a0 b2
	at23	r27, r19		; a1 b1
	at3	r26, r21		; a0 b3
	at3	r27, r20		; a1 b2
	eor	r1, r1
	ret
	.size	__mulsi3, .-__mulsi3
